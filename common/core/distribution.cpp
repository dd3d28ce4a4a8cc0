#include "core/distribution.h"

#include <algorithm>

namespace pf {

namespace {

// Largest cdf size that sampleDiscrete searches by counting.
constexpr size_t kLinearSearchMax = 16;

}  // namespace

Distribution1D::Distribution1D(const std::vector<double> &w) : func_(w), cdf_(w.size() + 1, 0.0) {
    for (size_t i = 0; i < w.size(); ++i) cdf_[i + 1] = cdf_[i] + std::max(0.0, w[i]);
    sum_ = cdf_.back();
    if (sum_ > 0)
        for (double &c : cdf_) c /= sum_;
    cdf_.back() = 1.0;
    pmf_.reserve(w.size());
    for (const double f : func_) pmf_.push_back(sum_ > 0 ? f / sum_ : 0.0);
}

size_t Distribution1D::sampleDiscrete(double u, double *pmfOut, double *uRemapped) const {
    // A single entry (a scene's only emitter) needs no search, and u stays as it is: the general remapping
    // below gives (u - 0) / (1 - 0), the same bits.
    if (func_.size() == 1) {
        const double p = pmf(0);
        if (pmfOut) *pmfOut = p;
        if (uRemapped) *uRemapped = p > 0 ? std::min(u, 0x1.fffffffffffffp-1) : 0;
        return 0;
    }
    // Largest index i with cdf[i] <= u, skipping zero-weight entries. A few entries (a mesh light's
    // triangles) are counted without branches: a binary search's branch on u is a coin toss for the
    // processor's predictor, and the count is the same index.
    std::ptrdiff_t atOrBelow;
    if (cdf_.size() <= kLinearSearchMax) {
        atOrBelow = 0;
        for (const double c : cdf_) atOrBelow += c <= u;
    } else {
        atOrBelow = std::upper_bound(cdf_.begin(), cdf_.end(), u) - cdf_.begin();
    }
    size_t i = static_cast<size_t>(std::max<std::ptrdiff_t>(0, atOrBelow - 1));
    i = std::min(i, func_.size() - 1);
    while (i > 0 && func_[i] <= 0) --i;
    const double p = pmf(i);
    if (pmfOut) *pmfOut = p;
    if (uRemapped) *uRemapped = p > 0 ? std::min((u - cdf_[i]) / (cdf_[i + 1] - cdf_[i]), 0x1.fffffffffffffp-1) : 0;
    return i;
}

double Distribution1D::sampleContinuous(double u, double *pdf, size_t *offset) const {
    double du;
    const size_t i = sampleDiscrete(u, nullptr, &du);
    if (offset) *offset = i;
    const double n = static_cast<double>(func_.size());
    if (pdf) *pdf = sum_ > 0 ? func_[i] * n / sum_ : 0.0;
    return (static_cast<double>(i) + du) / n;
}

double Distribution1D::pdfContinuous(double x) const {
    if (func_.empty() || sum_ <= 0) return 0.0;
    const double n = static_cast<double>(func_.size());
    const size_t i = std::min(static_cast<size_t>(std::max(0.0, x * n)), func_.size() - 1);
    return func_[i] * n / sum_;
}

Distribution2D::Distribution2D(const std::vector<double> &w, size_t nu, size_t nv) : nu_(nu), nv_(nv) {
    std::vector<double> marginal(nv);
    conditional_.reserve(nv);
    for (size_t v = 0; v < nv; ++v) {
        conditional_.emplace_back(std::vector<double>(w.begin() + v * nu, w.begin() + (v + 1) * nu));
        marginal[v] = conditional_.back().sum();
    }
    marginal_ = Distribution1D(marginal);
}

Vec2 Distribution2D::sample(const Vec2 &u, double *pdf) const {
    double pdfV, pdfU;
    size_t v;
    const double y = marginal_.sampleContinuous(u.y, &pdfV, &v);
    const double x = conditional_[v].sampleContinuous(u.x, &pdfU);
    if (pdf) *pdf = pdfU * pdfV;
    return {x, y};
}

double Distribution2D::pdf(const Vec2 &p) const {
    if (nv_ == 0 || marginal_.empty()) return 0.0;
    const size_t v = std::min(static_cast<size_t>(std::max(0.0, p.y * nv_)), nv_ - 1);
    return conditional_[v].pdfContinuous(p.x) * marginal_.pdfContinuous(p.y);
}

}  // namespace pf
