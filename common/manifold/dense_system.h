// A small dense linear system, solved by Gaussian elimination with partial pivoting: the Jacobians of specular
// chains with medium vertices (chain_jacobian.h, offset_jacobian.h), whose length rows break the 2x2
// block-tridiagonal structure of surface chains (ALGORITHMS.md §6.7). Chains are short, so O(n^3) is cheap.
#pragma once
#include <cstddef>
#include <vector>

namespace pf {

class DenseSystem {
public:
    explicit DenseSystem(size_t n) : n_(n), m_(n * n, 0.0) {}
    size_t size() const { return n_; }
    double &operator()(size_t r, size_t c) { return m_[r * n_ + c]; }
    double operator()(size_t r, size_t c) const { return m_[r * n_ + c]; }
    // Solves A X = B in place for the columns of b (n rows of `cols` entries each), leaving A eliminated. False
    // when a pivot is negligible against the largest entry of A (singular, like BlockTridiagonal's relative test).
    bool solve(std::vector<double> &b, size_t cols);
    // |det A|, by elimination of a copy (row swaps only flip the sign); 0 when singular in the sense above.
    double absDeterminant() const;

private:
    size_t n_;
    std::vector<double> m_;
};

}  // namespace pf
