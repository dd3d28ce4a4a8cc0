// The tangent space of the specular manifold and the generalized geometry term through a specular chain
// (ALGORITHMS.md §6.3, [TR eq. 9], [TH eq. 4.5]).
//
//     T_S = -A^{-1} [B_1 B_k]
//     G(x_1 <-> … <-> x_k) = |det(P_2 A^{-1} B_k)| G(x_1 <-> x_2) = |det(P_{k-1} A^{-1} B_1)| G(x_{k-1} <-> x_k)
//
// P_i selects vertex i's block row. With orthonormal charts the determinant is the ratio of a small area at
// x_2 to its preimage at x_k (with x_1 fixed), and G(x_1 <-> x_2) turns area at x_2 into projected solid angle
// at x_1. The result is in the area measure of both (non-specular) ends; visibility is the caller's business.
#pragma once
#include <optional>
#include <vector>

#include "manifold/chain_jacobian.h"

namespace pf {

struct TangentSpace {
    // Per unknown of the ChainJacobian (same order): ∂(u, v) of that vertex w.r.t. the chart of x_0
    // (zero when x_0 has no chart or is itself an unknown) and w.r.t. the chart of x_{k-1}.
    std::vector<Mat2> wrtFirst, wrtLast;
};

// T_S from a built ChainJacobian.
TangentSpace tangentSpace(const ChainJacobian &jacobian);

// The ordinary geometry term between two chain vertices, in the measures of the charts: |cos| at each end
// that is a Surface or VirtualPlane (1 for points and medium endpoints), over the squared distance; for a
// FixedDirection end, the parallel beam does not spread: |cos| at the other end only.
double geometryTerm(const ManifoldVertex &a, const ManifoldVertex &b);

// G(x_0 <-> … <-> x_{k-1}) for a chain with unconstrained ends (a FixedDirection end may be either one; the
// chain is reversed internally when it is the last). Equal to geometryTerm() for k = 2. nullopt when the chain
// is degenerate or A is singular.
std::optional<double> generalizedGeometry(const std::vector<ManifoldVertex> &chain);

}  // namespace pf
