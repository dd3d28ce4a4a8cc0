// The specular constraint of manifold exploration and its derivatives (ALGORITHMS.md §6.1-6.2, [TR §3.3, A2]).
//
// For a constrained Surface vertex x_i with neighbours x_{i-1}, x_{i+1} (chain order):
//
//     c_i = T(x_i)^T h_i,   h_i = γ(ω_i + eta ω_o),   T = [s t],  s = dp/du - <dp/du, n> n,  t = dp/dv - <dp/dv, n> n
//
// with ω_i, ω_o the unit directions towards x_{i-1} and x_{i+1}, n the shading normal and eta the vertex's
// relative index (manifold_vertex.h). h is normalized on purpose: the glossy extension recovers the microfacet
// normal from its tangent projection (§6.6). The constraint holds when c_i equals the vertex's offset o_i.
// For a FixedDirection endpoint, c_1 = T(x_1)^T γ(x_2 - x_1) with T its chart ⟂ d (§6.1).
//
// The derivatives are the three 2x2 blocks of ∇C in the vertex's row, with respect to the chart coordinates
// (u, v) of x_{i-1}, x_i and x_{i+1} (the TR listing's A, B, C; the thesis listing's dpdv/dndv typo is not
// reproduced). They assume orthonormal charts, which ManifoldVertex guarantees.
#pragma once
#include <optional>

#include "manifold/manifold_vertex.h"

namespace pf {

struct ConstraintDerivatives {
    Mat2 prev;  // ∂c_i / ∂(u, v) of x_{i-1} (sub-diagonal block)
    Mat2 self;  // ∂c_i / ∂(u, v) of x_i (diagonal block)
    Mat2 next;  // ∂c_i / ∂(u, v) of x_{i+1} (super-diagonal block)
};

// The generalized half-vector h_i = γ(ω_i + eta ω_o) of a constrained Surface vertex; nullopt when
// ω_i + eta ω_o vanishes (index-matched refraction, or a neighbour at the vertex).
std::optional<Vec3> generalizedHalfVector(const ManifoldVertex &prev, const ManifoldVertex &v,
                                          const ManifoldVertex &next);

// c_i (the constraint value, compare with v.offset) of a constrained vertex (Surface or FixedDirection).
// For a FixedDirection vertex, prev is ignored and next is x_2. nullopt on degenerate geometry.
std::optional<Vec2> constraintValue(const ManifoldVertex &prev, const ManifoldVertex &v, const ManifoldVertex &next);

// The three blocks of ∇C in v's row. For a FixedDirection vertex (the chain's first vertex), prev is ignored
// and its block is zero. Blocks w.r.t. a neighbour without a chart (FixedPosition) are zero. nullopt on
// degenerate geometry.
std::optional<ConstraintDerivatives> constraintDerivatives(const ManifoldVertex &prev, const ManifoldVertex &v,
                                                           const ManifoldVertex &next);

// The microfacet normal of the offset manifold (§6.6): the unit vector m with T^T m = offset and the sign of
// <m, n> given by v.halfVectorAbove. T's columns s, t are not orthonormal under shading normals, so the
// tangential part is solved from their Gram matrix. nullopt if |tangential part| >= 1.
std::optional<Vec3> microfacetNormal(const ManifoldVertex &v);

// Scatters the unit direction wi (pointing from the vertex towards where the light came from) about the unit
// normal m: reflection, or refraction with relative index eta = eta_o / eta_i (h ∝ wi + eta wo as above).
// nullopt on total internal reflection.
std::optional<Vec3> scatterAbout(const Vec3 &wi, const Vec3 &m, Scattering scattering, double eta);

}  // namespace pf
