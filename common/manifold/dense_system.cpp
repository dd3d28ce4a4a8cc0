#include "manifold/dense_system.h"

#include <algorithm>
#include <cmath>

namespace pf {

bool DenseSystem::solve(std::vector<double> &b, size_t cols) {
    double scale = 0;
    for (const double x : m_) scale = std::max(scale, std::abs(x));
    if (!(scale > 0) || !std::isfinite(scale)) return false;
    DenseSystem &a = *this;
    for (size_t k = 0; k < n_; ++k) {
        size_t pivot = k;
        for (size_t r = k + 1; r < n_; ++r)
            if (std::abs(a(r, k)) > std::abs(a(pivot, k))) pivot = r;
        if (!(std::abs(a(pivot, k)) > 1e-13 * scale)) return false;
        if (pivot != k) {
            for (size_t c = 0; c < n_; ++c) std::swap(a(k, c), a(pivot, c));
            for (size_t c = 0; c < cols; ++c) std::swap(b[k * cols + c], b[pivot * cols + c]);
        }
        for (size_t r = k + 1; r < n_; ++r) {
            const double f = a(r, k) / a(k, k);
            if (f == 0) continue;
            for (size_t c = k; c < n_; ++c) a(r, c) -= f * a(k, c);
            for (size_t c = 0; c < cols; ++c) b[r * cols + c] -= f * b[k * cols + c];
        }
    }
    for (size_t k = n_; k-- > 0;)
        for (size_t c = 0; c < cols; ++c) {
            double x = b[k * cols + c];
            for (size_t j = k + 1; j < n_; ++j) x -= a(k, j) * b[j * cols + c];
            b[k * cols + c] = x / a(k, k);
        }
    return true;
}

double DenseSystem::absDeterminant() const {
    DenseSystem a = *this;
    std::vector<double> none;
    if (!a.solve(none, 0)) return 0.0;
    double det = 1;
    for (size_t k = 0; k < n_; ++k) det *= a(k, k);
    return std::abs(det);
}

}  // namespace pf
