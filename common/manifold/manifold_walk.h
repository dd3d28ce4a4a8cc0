// WalkManifold (ALGORITHMS.md §6.4, [TR §4], [TH ch. 5]): moves the end x_n of a specular chain x_1 … x_n to
// a target x'_n while x_1 stays fixed, and updates the constrained vertices x_2 … x_{n-1} so that the path stays
// on its (offset) specular manifold.
//
// Predictor-corrector iteration with step control:
//     i = 0; β = 1
//     while ‖x_n − x'_n‖ > ε L:
//         predictor: move the first unknown by −β P_first A⁻¹ B_n T(x_n)ᵀ (x'_n − x_n) in its chart
//         corrector: trace a ray from x_1 through the predicted point (for a FixedDirection x_1: from the predicted
//                    x_1 along d) and reflect/refract through every constrained vertex about its offset microfacet
//                    normal; the last segment intersects the virtual plane instead of the scene
//         accept and set β = min(1, 2β) if the configuration is unchanged and x_n got closer, else β = β / 2
//         fail when i exceeds N
// ∇C is rebuilt at every iteration. The moving end lives on the symmetric virtual plane through x_n and x'_n
// (virtualPlane() in manifold_vertex.h), so walks x_n -> x'_n and back use the same plane; after convergence
// x_{n-1} must see x'_n.
//
// Configuration: each corrected vertex must lie on the same shape with the same BSDF, be hit from the same side
// of its geometric normal, and scatter the same way (reflection stays reflection on the same side, refraction
// crosses, no total internal reflection). Any change makes the corrector step fail (β halves). Any triangle of
// the same shape may be met: with interpolated normals the manifold continues smoothly across triangles, and on
// flat-shaded meshes (one normal per facet, a separate branch of the manifold per facet) a walk that steps onto
// another facet lands on a valid specular path too, and the perturbation's reverse walk decides whether such a
// move can be undone (on TORUS's glass cube most can: forbidding facet changes lowered the share of converged
// walks from 95% to 93% and the acceptance from 84% to 83%).
//
// Medium vertices (ALGORITHMS.md §6.7, [TR §7.1]): the corrector places a medium vertex at its segment length
// from its predecessor along the propagated direction, requires that no surface other than an index-matched one
// lies in between, and leaves it in the direction its offset gives in the frame of the new incoming direction. ∇C then
// has the length rows of chain_jacobian.h, so the predictor is the exact first-order model of the walked manifold.
//
// Index-matched boundaries (surfaces with the null BSDF, edge.h): chain segments pass straight through them, in the
// corrector, in propagation and in the final visibility check. A crossing does not bend the ray, so it is no
// vertex of the chain: ∇C, G and the offset Jacobian do not see it; the path-space edges that the perturbations
// rebuild from the walked chain carry its transmittance through both media and count it for the path's depth.
//
// Scene scale L: the seeds use L = max_i ‖x_i‖, which depends on where the world origin is (a scene translated
// far away would demand absurd relative accuracy). We use the diagonal of the scene's bounding box instead: a
// length of the scene's own size, invariant under translation, and the same for every walk (so the forward and
// reverse walks of a perturbation use the same tolerance). ε = 1e-7 and N = 20 as in [TR §4].
//
// Offset manifolds and tangent frames (ALGORITHMS.md §6.6, §9.2): glossy vertices keep their offset o in the
// continuous tangent frame of specular_constraint.h, whose derivatives ∇C includes exactly, so walks on offset
// manifolds converge quadratically on curved shapes too (bench_manifold_walk's "offset" rows measure it).
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "core/vector.h"
#include "manifold/manifold_vertex.h"
#include "scene/intersection.h"

namespace pf {

class Scene;

struct ManifoldWalkParameters {
    double epsilon = 1e-7;   // relative tolerance ε
    int maxIterations = 20;  // N
    // Scene-scale length L; <= 0 means the scene bounding box's diagonal.
    double sceneScale = 0.0;
};

enum class WalkStatus : uint8_t {
    Converged,         // x_n reached x'_n within ε L and x_{n-1} sees x'_n
    IterationLimit,    // more than N iterations
    SingularJacobian,  // A was singular at some iterate (a caustic fold)
    Occluded,          // converged, but x_{n-1} does not see x'_n
    InvalidChain,      // the chain or target cannot be walked (degenerate plane normal, bad layout, ...)
};

// Per-walk statistics; the manifold perturbation accumulates them into the Table 1 counters (§5.5).
struct WalkStatistics {
    bool converged = false;
    int iterations = 0;         // predictor-corrector iterations performed
    int chainSize = 0;          // number of constrained vertices walked
    int singularJacobians = 0;  // iterations that met a singular A (0 or 1: the walk stops there)
};

struct WalkResult {
    WalkStatus status = WalkStatus::InvalidChain;
    // On success: the new chain x_1 … x_n, with x_n the target vertex; constrained vertices are Surface
    // vertices with full intersections (its) and the offsets, signs and scattering of the input chain.
    std::vector<ManifoldVertex> chain;
    WalkStatistics stats;
    bool converged() const { return status == WalkStatus::Converged; }
};

// The first surface along `ray` that is not index-matched (a BSDF other than the null one), into its; false when
// there is none before ray.tmax. ray.d must be a unit vector. The crossings keep the ray's line exactly.
bool intersectOpaque(const Scene &scene, Ray ray, Intersection &its);

class ManifoldWalk {
public:
    explicit ManifoldWalk(const Scene &scene, const ManifoldWalkParameters &params = {});

    // Walks chain (x_1 fixed first, x_n last; x_2 … x_{n-1} constrained, see chain_jacobian.h for the layout)
    // so that its end reaches `target`, a Surface (or MediumEndpoint) vertex with the end's normal convention.
    // A chain without unknowns (n = 2 and a start that is not FixedDirection) only needs the visibility check;
    // with a FixedDirection start, x_1 itself is walked on its plane ⟂ d.
    WalkResult walk(const std::vector<ManifoldVertex> &chain, const ManifoldVertex &target) const;

    // The propagation of the corrector and of the perturbation's first chain (§6.5): traces from the chain's
    // first vertex in unit direction d (for a FixedDirection first vertex: from `origin`, which replaces its
    // position, along its fixed direction; otherwise origin is ignored) through the constrained vertices of
    // `chain`, each scattered about its offset microfacet normal and required to keep its configuration (see
    // above). The vertex after the last constrained one is found by intersecting `endPlane` when given (a
    // VirtualPlane vertex) and the scene otherwise; then it is returned as an unconstrained Surface vertex with
    // its intersection. Returns the new chain, or nullopt when the configuration changes or a ray escapes.
    std::optional<std::vector<ManifoldVertex>> propagate(const std::vector<ManifoldVertex> &chain, const Vec3 &origin,
                                                         const Vec3 &d, const ManifoldVertex *endPlane) const;

    double sceneScale() const { return scale_; }
    const ManifoldWalkParameters &parameters() const { return params_; }

private:
    const Scene &scene_;
    ManifoldWalkParameters params_;
    double scale_;
};

}  // namespace pf
