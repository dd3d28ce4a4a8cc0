// The constraint of a single specular vertex between two fixed points, in the two forms specular manifold
// sampling solves with Newton's method (ALGORITHMS.md §7.1 "Improved constraint", [SMS §4.3, eqs. 10-12]):
//
// * Angle difference [SMS eq. 12]: with ω_i, ω_o the unit directions from the vertex x towards a (the
//   receiver x_1) and b (the emitter point x_3), and S(ω_i) the ideal outgoing direction by the mirror law or
//   Snell's law about the shading normal, C = (θ(S(ω_i)) - θ(ω_o), φ(S(ω_i)) - φ(ω_o)), Δφ wrapped into
//   [-π, π]. On total internal reflection of ω_i the roles swap: C compares S(ω_o) (with 1/η) with ω_i.
//   The spherical angles are taken in a local frame, not in world coordinates as the reference code does
//   (SMS_PORTAL_NOTES.md §1.7.3: its constraint is singular for directions along world ±z): by default the
//   frame puts the compared direction on its equator, at φ = 0, so that near a root both vectors are π/2
//   away from the poles and Δφ is away from the wrap. C = 0 iff S(ω_i) = ω_o, whatever the frame, so the
//   roots are those of the world-frame form.
// * Half-vector [SMS eq. 1] = [TR §3.3]: c = T^T h of specular_constraint.h.
//
// Both come with the 2x2 derivative with respect to the vertex's chart coordinates (u, v) (ManifoldVertex's
// orthonormal chart, first-order model x = p + u dp/du + v dp/dv, n = n + u dn/du + v dn/dv of §6.2), with a
// and b fixed: that is the whole Newton system of a one-vertex chain. chainConstraint() adds the derivatives with
// respect to the neighbours' charts, the off-diagonal blocks of a chain of several vertices. The angle form is
// differentiated exactly by forward-mode dual numbers, so no hand-derived formula can drift from the value.
#pragma once
#include <optional>

#include "core/frame.h"
#include "manifold/manifold_vertex.h"

namespace pf {

enum class SmsConstraint { AngleDifference, HalfVector };

struct ConstraintJet {
    Vec2 value;
    Mat2 derivative;  // ∂C / ∂(u, v) of the vertex
};

// The angle-difference constraint at v (Reflection or Refraction with its eta = eta_o / eta_i, chain order
// a -> v -> b) in `frame` (nullptr: the frame with the compared direction at θ = π/2, φ = 0). nullopt on
// degenerate geometry (a neighbour at the vertex) or when both directions are totally internally reflected.
std::optional<ConstraintJet> angleDifferenceConstraint(const Vec3 &a, const ManifoldVertex &v, const Vec3 &b,
                                                       const Frame *frame = nullptr);

// The constraint at a vertex v of a chain prev -> v -> next of several specular vertices with its three blocks
// of ∇C, with respect to the charts of prev, v and next (zero for a vertex without chart): the block row of v
// in the block-tridiagonal Newton system of the chain (block_tridiagonal.h, [SMS §5.6], [TR §3.3]).
struct ChainConstraint {
    Vec2 value;
    Mat2 prev, self, next;
};
// The angle form's `frame` as in angleDifferenceConstraint() (the half-vector form has none).
std::optional<ChainConstraint> chainConstraint(SmsConstraint form, const ManifoldVertex &prev, const ManifoldVertex &v,
                                               const ManifoldVertex &next, const Frame *frame = nullptr);

// The half-vector constraint T^T h at v and its diagonal block of ∇C (specular_constraint.h).
std::optional<ConstraintJet> halfVectorConstraint(const Vec3 &a, const ManifoldVertex &v, const Vec3 &b);

}  // namespace pf
