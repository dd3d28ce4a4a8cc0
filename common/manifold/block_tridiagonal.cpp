#include "manifold/block_tridiagonal.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace pf {

namespace {

// Determinant of a dense row-major n x n matrix by Gaussian elimination with partial pivoting (the small
// submatrices of A^{-1} in the glossy determinant factor; n = 2 * number of selected blocks).
double denseDeterminant(std::vector<double> a, size_t n) {
    double det = 1.0;
    for (size_t k = 0; k < n; ++k) {
        size_t pivot = k;
        for (size_t r = k + 1; r < n; ++r)
            if (std::abs(a[r * n + k]) > std::abs(a[pivot * n + k])) pivot = r;
        if (a[pivot * n + k] == 0.0) return 0.0;
        if (pivot != k) {
            for (size_t c = 0; c < n; ++c) std::swap(a[k * n + c], a[pivot * n + c]);
            det = -det;
        }
        const double akk = a[k * n + k];
        det *= akk;
        for (size_t r = k + 1; r < n; ++r) {
            const double f = a[r * n + k] / akk;
            for (size_t c = k + 1; c < n; ++c) a[r * n + c] -= f * a[k * n + c];
        }
    }
    return det;
}

// Forward and back substitution with the block LU factors, for one (Vec2) or two (Mat2) right-hand sides:
// L y = b with L's sub-diagonal blocks L_i, then U x = y with U's diagonal D_i and super-diagonal upper(i).
template <typename T>
void substitute(const std::vector<Mat2> &factor, const std::vector<Mat2> &pivotInv, const std::vector<Mat2> &upper,
                std::vector<T> &b) {
    const size_t n = pivotInv.size();
    for (size_t i = 1; i < n; ++i) b[i] = b[i] - factor[i] * b[i - 1];
    for (size_t i = n; i-- > 0;) {
        if (i + 1 < n) b[i] = b[i] - upper[i] * b[i + 1];
        b[i] = pivotInv[i] * b[i];
    }
}

}  // namespace

void BlockTridiagonal::resize(size_t blocks) {
    lower_.assign(blocks, Mat2());
    diag_.assign(blocks, Mat2());
    upper_.assign(blocks, Mat2());
    pivotInv_.clear();
    factor_.clear();
    factorized_ = false;
}

bool BlockTridiagonal::factorize() {
    const size_t n = size();
    pivotInv_.assign(n, Mat2());
    factor_.assign(n, Mat2());
    factorized_ = false;
    for (size_t i = 0; i < n; ++i) {
        Mat2 pivot = diag_[i];
        double scale = pivot.frobeniusNormSquared();
        if (i > 0) {
            factor_[i] = lower_[i] * pivotInv_[i - 1];
            const Mat2 update = factor_[i] * upper_[i - 1];
            pivot = pivot - update;
            scale = std::max(scale, update.frobeniusNormSquared());
        }
        if (!pivot.invert(pivotInv_[i], scale)) return false;
    }
    factorized_ = true;
    return true;
}

double BlockTridiagonal::determinant() const {
    double det = 1.0;
    for (const Mat2 &inv : pivotInv_) det /= inv.determinant();
    return det;
}

void BlockTridiagonal::solve(std::vector<Vec2> &b) const { substitute(factor_, pivotInv_, upper_, b); }

void BlockTridiagonal::solve(std::vector<Mat2> &b) const { substitute(factor_, pivotInv_, upper_, b); }

std::vector<Mat2> BlockTridiagonal::inverseColumn(size_t j) const {
    std::vector<Mat2> column(size());
    column[j] = Mat2::identity();
    solve(column);
    return column;
}

double BlockTridiagonal::inverseSubmatrixDeterminant(const std::vector<size_t> &blocks) const {
    const size_t m = blocks.size(), n = 2 * m;
    std::vector<double> dense(n * n);
    for (size_t c = 0; c < m; ++c) {
        const std::vector<Mat2> column = inverseColumn(blocks[c]);
        for (size_t r = 0; r < m; ++r)
            for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j) dense[(2 * r + i) * n + 2 * c + j] = column[blocks[r]](i, j);
    }
    return denseDeterminant(std::move(dense), n);
}

}  // namespace pf
