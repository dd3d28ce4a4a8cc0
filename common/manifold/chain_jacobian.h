// ∇C of a specular chain, partitioned as in [TR §3.3] / ALGORITHMS.md §6.2: the square block-tridiagonal
// middle A over the chain's constrained vertices and the columns B_1, B_k of its two ends.
//
// A chain is x_0 … x_{k-1} (k >= 2) in chain order. Its unknowns, the block rows and columns of A, are the
// constrained interior vertices x_1 … x_{k-2}, preceded by x_0 when x_0 is a FixedDirection endpoint (its
// position on the plane ⟂ d is then determined by the chain, §6.1). Every interior vertex must be constrained;
// x_{k-1} must not be, and FixedDirection may only be the first vertex (reverse the chain otherwise).
#pragma once
#include <vector>

#include "manifold/block_tridiagonal.h"
#include "manifold/manifold_vertex.h"

namespace pf {

struct ChainJacobian {
    // Chain indices of A's block rows and columns, in order.
    std::vector<size_t> unknowns;
    BlockTridiagonal a;
    // B_1 = ∂c/∂x_0: nonzero only in A's first block row; zero when x_0 is an unknown or has no chart.
    Mat2 bFirst;
    // B_k = ∂c/∂x_{k-1}: nonzero only in A's last block row.
    Mat2 bLast;
    // After a failed build(): true when the layout and geometry were fine but A is singular.
    bool singular = false;

    // Fills unknowns, A (factorized), bFirst and bLast for `chain`. Returns false on an invalid chain layout,
    // degenerate geometry (a vanishing half-vector or edge) or a singular A.
    bool build(const std::vector<ManifoldVertex> &chain);
};

}  // namespace pf
