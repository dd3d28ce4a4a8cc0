// The tangent space of the specular manifold and the generalized geometry term through a specular chain
// (ALGORITHMS.md §6.3, [TR eq. 9], [TH eq. 4.5]).
//
//     T_S = -A^{-1} [B_1 B_k]
//     G(x_1 -> … -> x_k) = |det(P_2 A^{-1} B_k)| G(x_1 <-> x_2)
//
// P_i selects vertex i's block row. With orthonormal charts the determinant is the ratio of a small area at
// x_2 to its preimage at x_k (with x_1 fixed), and G(x_1 <-> x_2) turns area at x_2 into projected solid angle
// at x_1: the result is the projected solid angle at x_1 per unit area at x_k.
//
// The term has a direction. [TR eq. 9] writes the other form |det(P_{k-1} A^{-1} B_1)| G(x_{k-1} <-> x_k), the
// projected solid angle at x_k per unit area at x_1, as equal; that holds for reflections only. Through
// refractions the étendue η² dA dΩ⊥ is what is conserved, so
//
//     G(x_1 -> … -> x_k) = (η_k / η_1)² G(x_k -> … -> x_1),
//
// η_1, η_k the refractive indices of the media at x_1 and at x_k (tests/test_manifold_walk.cpp checks both
// directions against traced finite differences and their ratio). Callers pick the direction by the order in
// which they list the chain: generalizedGeometry(x_1 … x_k) is G(x_1 -> … -> x_k); reversedChain() (in
// manifold_vertex.h) gives the other one. Visibility is the caller's business.
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

// T_S from a built ChainJacobian of a chain without medium vertices (empty for the dense system of a chain
// with medium vertices, chain_jacobian.h).
TangentSpace tangentSpace(const ChainJacobian &jacobian);

// The ordinary geometry term between two chain vertices, in the measures of the charts: |cos| at each end
// that is a Surface or VirtualPlane (1 for points and medium endpoints), over the squared distance; for a
// FixedDirection end, the parallel beam does not spread: |cos| at the other end only.
double geometryTerm(const ManifoldVertex &a, const ManifoldVertex &b);

// G(x_0 -> … -> x_{k-1}), the projected solid angle at x_0 per unit area at x_{k-1} (see above), for a chain
// with unconstrained ends. A FixedDirection end may be either one: its measure is the beam's cross-section, and
// the chain is reversed internally (reversedChain()) when it is the last, which gives the same value (a parallel
// beam's cross-section per unit area at the other end). Equal to geometryTerm() for k = 2. nullopt when the
// chain is degenerate or A is singular. Through medium vertices (§6.7) the chain is the set of paths with their
// offsets and segment lengths held: G is then the projected solid angle at x_0 per unit area at x_{k-1} among
// those paths.
std::optional<double> generalizedGeometry(const std::vector<ManifoldVertex> &chain);

}  // namespace pf
