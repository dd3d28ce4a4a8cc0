// ∇C of a specular chain, partitioned as in [TR §3.3] / ALGORITHMS.md §6.2: the square block-tridiagonal
// middle A over the chain's constrained vertices and the columns B_1, B_k of its two ends.
//
// A chain is x_0 … x_{k-1} (k >= 2) in chain order. Its unknowns, the block rows and columns of A, are the
// constrained interior vertices x_1 … x_{k-2}, preceded by x_0 when x_0 is a FixedDirection endpoint (its
// position on the plane ⟂ d is then determined by the chain, §6.1). Every interior vertex must be constrained;
// x_{k-1} must not be, and FixedDirection may only be the first vertex (reverse the chain otherwise).
//
// Medium vertices (§6.7, [TR §7]) have three coordinates, their chart ⟂ ω_in and the axis ω_in, and three rows:
// the two of the medium constraint and the fixed segment length <ω_in, δx_i - δx_{i-1}> = 0. The length row
// couples a medium vertex's axis to every coordinate of its predecessor, so after elimination a run of medium
// vertices couples each constraint to all earlier vertices and A is no longer block-tridiagonal with 2x2 blocks.
// A chain with medium vertices is therefore solved as one dense system (chains are short: a few dozen rows),
// with the same result, firstFromLast; A, bFirst and bLast are then left empty.
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
    // P_first A^{-1} B_k: how the chart coordinates of the first unknown move per unit step of x_{k-1}'s chart
    // (T_S up to sign; for a medium first unknown, its chart ⟂ ω_in: its axis does not move while x_0 stays).
    Mat2 firstFromLast;
    // Whether the chain has medium vertices (the dense solve above).
    bool dense = false;
    // After a failed build(): true when the layout and geometry were fine but A is singular.
    bool singular = false;

    // Fills unknowns, A (factorized), bFirst, bLast and firstFromLast for `chain`. Returns false on an invalid
    // chain layout, degenerate geometry (a vanishing half-vector or edge) or a singular A.
    bool build(const std::vector<ManifoldVertex> &chain);

private:
    bool buildDense(const std::vector<ManifoldVertex> &chain);
};

}  // namespace pf
