// The specular constraint of manifold exploration and its derivatives (ALGORITHMS.md §6.1-6.2, [TR §3.3, A2]).
//
// For a constrained Surface vertex x_i with neighbours x_{i-1}, x_{i+1} (chain order):
//
//     c_i = T(x_i)^T h_i,   h_i = γ(ω_i + eta ω_o),   T = [s t]
//
// with ω_i, ω_o the unit directions towards x_{i-1} and x_{i+1}, n the shading normal and eta the vertex's
// relative index (manifold_vertex.h). h is normalized on purpose: the glossy extension recovers the microfacet
// normal from its tangent projection (§6.6). The constraint holds when c_i equals the vertex's offset o_i.
// For a FixedDirection endpoint, c_1 = T(x_1)^T γ(x_2 - x_1) with T its chart ⟂ d (§6.1).
//
// The tangent frame T spans the shading tangent plane. Two frame fields are used:
// * Ideal specular vertices (o = 0): [TR A2]'s s = dp/du - <dp/du, n> n, t = dp/dv - <dp/dv, n> n from the
//   orthonormal chart. Where c = 0 only the plane T spans matters (h ∥ n), not how T turns within it, so the
//   chart's own turning (spherical coordinates, the per-triangle charts of a mesh) never affects the solution.
// * Glossy vertices on offset manifolds (ManifoldVertex::glossy): there o ≠ 0 is a vector in T's coordinates,
//   so the frame field defines the manifold and must be continuous and differentiated exactly. The chart's frame
//   is neither: it jumps across mesh triangles (one chart per triangle), and ∇C's first-order model keeps the
//   chart vectors fixed, which misses how spherical or polar coordinates turn within the tangent plane (the
//   walk then converges only linearly). Instead ŝ = γ(a - <a, n> n) for a fixed direction a and t = n × ŝ: a
//   function of the shading normal alone (continuous across triangles with interpolated normals, ALGORITHMS.md
//   §9.2 "continuous tangent frames"), whose derivatives follow exactly from dn/du and dn/dv, so that ∇C is
//   exact for the offset manifold and the walk converges quadratically. It is undefined only where n = ±a
//   (functions below return nullopt there).
//
// Medium vertices (ALGORITHMS.md §6.7, [TR §7 eq. 27]): c_i = T(ω_in)^T ω_out, ω_in = γ(x_i - x_{i-1}) the
// direction of travel into the vertex and ω_out = γ(x_{i+1} - x_i), with T(ω) = [ŝ, ω × ŝ], ŝ = γ(a - <a, ω> ω)
// for the fixed direction a of the glossy frame above: continuous in ω, so that offsets o ≠ 0 (every medium
// vertex has one: its scattering angle) mean the same across a walk. It depends on x_{i-1} through ω_in as well.
// A medium vertex has three coordinates: its chart (the frame T(ω_in), ⟂ ω_in) and the axis ω_in; the
// `*Axis` columns below are the derivatives along the axis of each neighbour that is a medium vertex, which the
// length rows of chain_jacobian.h need.
//
// The derivatives are the three 2x2 blocks of ∇C in the vertex's row, with respect to the chart coordinates
// (u, v) of x_{i-1}, x_i and x_{i+1} (the TR listing's A, B, C; the thesis listing's dpdv/dndv typo is not
// reproduced). They assume orthonormal charts, which ManifoldVertex guarantees. The frame's choice changes
// each row of ∇C by an invertible 2x2 factor only, so T_S and the generalized geometry term do not depend on it.
#pragma once
#include <optional>
#include <utility>

#include "manifold/manifold_vertex.h"

namespace pf {

struct ConstraintDerivatives {
    Mat2 prev;  // ∂c_i / ∂(u, v) of x_{i-1} (sub-diagonal block)
    Mat2 self;  // ∂c_i / ∂(u, v) of x_i (diagonal block)
    Mat2 next;  // ∂c_i / ∂(u, v) of x_{i+1} (super-diagonal block)
    // ∂c_i along the axis n (= ω_in) of x_{i-1}, x_i, x_{i+1} where that vertex is a Medium vertex; else zero.
    Vec2 prevAxis, selfAxis, nextAxis;
};

// The constraint frame T(ω) = [ŝ, ω × ŝ] of a medium vertex whose incoming direction is the unit vector ω;
// nullopt where ω is parallel to the frame's fixed direction.
std::optional<std::pair<Vec3, Vec3>> mediumFrame(const Vec3 &w);

// The generalized half-vector h_i = γ(ω_i + eta ω_o) of a constrained Surface vertex; nullopt when
// ω_i + eta ω_o vanishes (index-matched refraction, or a neighbour at the vertex).
std::optional<Vec3> generalizedHalfVector(const ManifoldVertex &prev, const ManifoldVertex &v,
                                          const ManifoldVertex &next);

// c_i (the constraint value, compare with v.offset) of a constrained vertex (Surface, Medium or FixedDirection),
// from the positions alone (a Medium vertex's frame is rebuilt from prev and v).
// For a FixedDirection vertex, prev is ignored and next is x_2. nullopt on degenerate geometry.
std::optional<Vec2> constraintValue(const ManifoldVertex &prev, const ManifoldVertex &v, const ManifoldVertex &next);

// The three blocks of ∇C in v's row. For a FixedDirection vertex (the chain's first vertex), prev is ignored
// and its block is zero. Blocks w.r.t. a neighbour without a chart (FixedPosition) are zero. nullopt on
// degenerate geometry.
std::optional<ConstraintDerivatives> constraintDerivatives(const ManifoldVertex &prev, const ManifoldVertex &v,
                                                           const ManifoldVertex &next);

// The microfacet normal of the offset manifold (§6.6): the unit vector m with T^T m = offset and the sign of
// <m, n> given by v.halfVectorAbove. The chart frame's columns s, t are not orthonormal under shading normals,
// so the tangential part is solved from their Gram matrix. nullopt if |tangential part| >= 1.
std::optional<Vec3> microfacetNormal(const ManifoldVertex &v);

// Scatters the unit direction wi (pointing from the vertex towards where the light came from) about the unit
// normal m: reflection, or refraction with relative index eta = eta_o / eta_i (h ∝ wi + eta wo as above);
// at a Medium vertex m is the outgoing direction itself (microfacetNormal() of a medium vertex is T o ± ... ω_in).
// nullopt on total internal reflection.
std::optional<Vec3> scatterAbout(const Vec3 &wi, const Vec3 &m, Scattering scattering, double eta);

}  // namespace pf
