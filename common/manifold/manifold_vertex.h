// A vertex of a specular chain for manifold exploration (ALGORITHMS.md §6.1-6.4, [TR §3.3, A2]).
//
// Every vertex carries a locally orthonormal chart of its tangent plane: dp/du and dp/dv are orthonormalized
// (Gram-Schmidt), and the same 2x2 map is applied to dn/du and dn/dv, so that a unit step in (u, v) is a unit
// step in area and no extra area determinants enter the generalized geometry term (§6.2). The specular
// constraint (specular_constraint.h) uses the shading normal n and its derivatives; the chart spans the
// geometric tangent plane, so G is in the area measure of the geometric surface.
//
// Vertex kinds:
// * Surface: a point on a shape. A constrained (specular or glossy-treated-as-specular) vertex stores how it
//   scatters (reflection or refraction with the relative index eta = eta_o / eta_i of §6.1), and its offset o:
//   the tangent projection of the generalized half-vector, zero for an ideal specular vertex and the current
//   value for a glossy vertex walked on its offset manifold (§6.6), together with the sign of the half-vector's
//   normal component. An unconstrained Surface vertex is a non-specular chain endpoint.
// * VirtualPlane: the moving endpoint of WalkManifold, on the plane through x_n and x'_n with the symmetric
//   normal of §6.4 (virtualPlane() below). Its chart is orthonormal by construction and its normal constant.
// * FixedPosition: a point light or pinhole: the position is fixed and has no chart (zero columns in ∇C).
// * FixedDirection: a directional light or orthographic camera: the direction d of the edge towards the chain
//   is fixed. The position moves on the plane perpendicular to d (chart dp/du, dp/dv ⟂ d, n = d), and the
//   vertex has the endpoint constraint c = T^T ω(x_1 -> x_2) = 0 of §6.1.
// * MediumEndpoint: a non-specular endpoint inside a medium, parameterized on the plane perpendicular to the
//   direction facing the chain (§6.7), so that its cosine factor is 1 as in the medium's geometry term.
// * Medium: a medium interaction treated as part of a chain ([TR §7], [TH ch. 7], ALGORITHMS.md §6.7). A strongly
//   forward-scattering phase function is a rough mirror in the scattering angle: the constraint is
//   c = T(ω_in)^T ω_out with ω_in the direction of travel into the vertex (from its chain predecessor) and
//   ω_out the direction towards its successor, held at the vertex's offset o (the scattering direction in the
//   frame of the incoming one; specular_constraint.h). Its third degree of freedom is removed by holding the
//   distance to the predecessor (`segment`) fixed. n = ng = ω_in; the chart dp/du, dp/dv is the constraint's
//   own frame T(ω_in), orthonormal and ⟂ ω_in (the tangent plane of the sphere of radius `segment` about the
//   predecessor), and halfVectorAbove is the sign of <ω_out, ω_in> (forward or backward scattering).
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "core/vector.h"
#include "manifold/mat2.h"
#include "scene/intersection.h"

namespace pf {

struct PathVertex;

enum class ManifoldVertexType : uint8_t {
    Surface,
    VirtualPlane,
    FixedPosition,
    FixedDirection,
    MediumEndpoint,
    Medium
};

// How a constrained vertex scatters; None for unconstrained vertices (non-specular endpoints), Medium for
// medium vertices in a chain (phase-function scattering, §6.7).
enum class Scattering : uint8_t { None, Reflection, Refraction, Medium };

struct ManifoldVertex {
    ManifoldVertexType type = ManifoldVertexType::Surface;
    Vec3 p;           // position
    Vec3 ng;          // geometric normal (as oriented by the shape); the plane normal; d for FixedDirection
    Vec3 n;           // shading normal: the normal of the constraint's tangent frame (§6.1)
    Vec3 dpdu, dpdv;  // orthonormal chart of the tangent plane (zero for FixedPosition)
    Vec3 dndu, dndv;  // shading-normal derivatives in the same chart

    Scattering scattering = Scattering::None;
    // Relative index of refraction eta_o / eta_i of §6.1 (h ∝ ω_i + eta ω_o, ω_i towards the predecessor,
    // ω_o towards the successor in chain order); 1 for reflection.
    double eta = 1.0;
    // Offset manifold S_o (§6.6): the constraint's target value. Zero for ideal specular vertices.
    Vec2 offset;
    // Whether the vertex is walked on its offset manifold (a glossy vertex treated as specular, §6.6). Its
    // offset is then measured in the continuous tangent frame of specular_constraint.h, which is a function of
    // the shading normal alone, instead of [TR A2]'s frame from the chart (see there for why).
    bool glossy = false;
    // Sign of <h, n> of the half-vector the offset was taken from: with o it recovers the microfacet normal
    // m = o_x s + o_y t ± sqrt(1 - |o|^2) n (microfacetNormal() in specular_constraint.h).
    bool halfVectorAbove = true;
    // Which side of the geometric normal the predecessor lies on (sign of <ω_i, ng>); part of the
    // configuration, since it decides eta and whether a ray hits the surface from outside or inside.
    bool predecessorAbove = true;
    // Medium vertices: the distance to the chain predecessor, which walks and propagation hold fixed (§6.7).
    double segment = 0.0;

    // The full intersection of Surface vertices, for callers that build PathVertex records from a walk's
    // result; its.shape and its.bsdf() identify the vertex's configuration.
    Intersection its;

    bool isConstrained() const { return scattering != Scattering::None || type == ManifoldVertexType::FixedDirection; }
    // Whether the vertex has two degrees of freedom (a chart); FixedPosition has none.
    bool hasChart() const { return type != ManifoldVertexType::FixedPosition; }
    const Shape *shape() const { return its.shape; }

    // A Surface vertex from an intersection, with its chart orthonormalized (§6.2). Non-specular endpoints
    // pass Scattering::None; constrained vertices pass how they scatter and the relative eta (see eta above).
    // Returns nullopt when dp/du and dp/dv are degenerate (rank < 2) for a constrained vertex, which needs
    // its normal derivatives; an unconstrained vertex then falls back to a frame around the normal.
    static std::optional<ManifoldVertex> surface(const Intersection &its, Scattering scattering = Scattering::None,
                                                 double eta = 1.0);
    // A constrained Surface vertex between neighbours at positions prev and next (in chain order): reflection
    // when both lie on the same side of the geometric normal, refraction otherwise, with eta from the BSDF's
    // interior/exterior ratio and the side prev lies on; the offset and its sign are set from the current
    // half-vector, so that a glossy vertex stays on its offset manifold (pass ideal = true to force o = 0 for
    // ideal specular vertices; ideal = false sets `glossy`). Returns nullopt on a degenerate chart, frame or
    // half-vector.
    static std::optional<ManifoldVertex> constrained(const Intersection &its, const Vec3 &prev, const Vec3 &next,
                                                     bool ideal);
    static ManifoldVertex fixedPosition(const Vec3 &p);
    // A directional endpoint at p whose edge towards the chain has the fixed unit direction d.
    static ManifoldVertex fixedDirection(const Vec3 &p, const Vec3 &d);
    // A medium vertex in a chain at p between neighbours at prev and next (chain order), with its current
    // offset and segment length (§6.7). nullopt when a neighbour coincides with p or the frame is degenerate.
    static std::optional<ManifoldVertex> medium(const Vec3 &p, const Vec3 &prev, const Vec3 &next);
    // A medium vertex's incoming direction w (unit): n = ng = w and the chart T(w). False where the frame is
    // degenerate.
    bool setIncoming(const Vec3 &w);
    // A non-specular medium endpoint at p whose chain neighbour lies at `toward`.
    static std::optional<ManifoldVertex> mediumEndpoint(const Vec3 &p, const Vec3 &toward);
    // A non-specular endpoint from a path-space vertex: surfaces and area-light or aperture positions become
    // Surface vertices, point lights and pinholes FixedPosition, directional emitters FixedDirection (edge
    // towards `neighbour`), medium vertices MediumEndpoint. Returns nullopt for supernodes.
    static std::optional<ManifoldVertex> endpoint(const PathVertex &v, const Vec3 &neighbour);
};

// The chain listed the other way round. The constrained vertices' eta and predecessorAbove are relative to chain
// order, so a refraction's eta becomes 1 / eta and its predecessor's side flips; the half-vector
// γ(ω_i + eta ω_o) keeps its direction (γ(ω_o + ω_i / eta) is parallel to it), and with it the offset. A medium
// vertex's frame, offset and segment are relative to its predecessor, so it is rebuilt from its new neighbours.
std::vector<ManifoldVertex> reversedChain(const std::vector<ManifoldVertex> &chain);

// The symmetric virtual plane of WalkManifold (§6.4, [TR §4]) through the current endpoint position p (normal
// n) and the target p' (normal n'): n_plane = γ(γ(n + n') - d <γ(n + n'), d>), d = γ(p' - p), with n' flipped
// first if <n, n'> < 0 (as Mitsuba does) and geometric normals. Swapping the two ends gives the same plane up
// to the normal's sign, so the walks x -> x' and x' -> x use the same plane. Returns the VirtualPlane vertex at
// p, or nullopt when the normal has (near) zero length.
std::optional<ManifoldVertex> virtualPlane(const Vec3 &p, const Vec3 &n, const Vec3 &pTarget, const Vec3 &nTarget);

}  // namespace pf
