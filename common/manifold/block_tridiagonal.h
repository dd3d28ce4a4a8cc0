// Block-tridiagonal matrices with 2x2 blocks and their LU factorization (ALGORITHMS.md §6.2-6.4, §6.6;
// [TR §4]: "a block tridiagonal LU factorization ... reduces the time complexity from O(n^3) to O(n)").
//
// The matrix A of a specular chain (the square middle of ∇C) couples each constrained vertex only to its
// neighbours. Block row i holds lower(i) = ∂c_i/∂x_{i-1} (i >= 1), diag(i) = ∂c_i/∂x_i and
// upper(i) = ∂c_i/∂x_{i+1} (i < n-1). The factorization is block Gaussian elimination without pivoting
// between block rows (each pivot block is inverted exactly): D_0 = diag(0),
// D_i = diag(i) - lower(i) D_{i-1}^{-1} upper(i-1). A pivot block that is singular relative to the scale of the
// terms it is made of makes factorize() fail, which callers treat as a singular A (a caustic fold, §6.3) instead of
// producing NaN.
#pragma once
#include <cstddef>
#include <vector>

#include "manifold/mat2.h"

namespace pf {

class BlockTridiagonal {
public:
    explicit BlockTridiagonal(size_t blocks = 0) { resize(blocks); }
    // Resizes to n x n blocks, all zero, and drops any factorization.
    void resize(size_t blocks);
    size_t size() const { return diag_.size(); }

    Mat2 &lower(size_t i) { return lower_[i]; }
    Mat2 &diag(size_t i) { return diag_[i]; }
    Mat2 &upper(size_t i) { return upper_[i]; }
    const Mat2 &lower(size_t i) const { return lower_[i]; }
    const Mat2 &diag(size_t i) const { return diag_[i]; }
    const Mat2 &upper(size_t i) const { return upper_[i]; }

    // Factorizes the current blocks (edits to the blocks afterwards require a new call). Returns false when
    // a pivot block is singular; solve()/determinant()/inverse queries require a successful factorization.
    bool factorize();
    bool factorized() const { return factorized_; }

    // det(A) = Π det(D_i).
    double determinant() const;
    // Solves A x = b in place; b has one 2-vector per block row.
    void solve(std::vector<Vec2> &b) const;
    // Solves A X = B in place for a block column B (one 2x2 block per block row, i.e. two right-hand sides).
    void solve(std::vector<Mat2> &b) const;
    // Block column j of A^{-1} (one 2x2 block per block row).
    std::vector<Mat2> inverseColumn(size_t j) const;
    // det of the submatrix of A^{-1} made of the block rows and columns listed in `blocks` (the glossy
    // determinant factor of [TR eq. 12], §6.6, keeps x_b's and the glossy vertices' rows and columns).
    double inverseSubmatrixDeterminant(const std::vector<size_t> &blocks) const;

private:
    std::vector<Mat2> lower_, diag_, upper_;
    std::vector<Mat2> pivotInv_;  // D_i^{-1}
    std::vector<Mat2> factor_;    // L_i = lower(i) D_{i-1}^{-1} (the unit lower factor's sub-diagonal blocks)
    bool factorized_ = false;
};

}  // namespace pf
