#include "manifold/manifold_walk.h"

#include <algorithm>

#include "bsdf/bsdf.h"
#include "manifold/chain_jacobian.h"
#include "manifold/specular_constraint.h"
#include "scene/crossings.h"
#include "scene/scene.h"

namespace pf {

namespace {

// A ray leaving a chain vertex at `origin` in direction d. The origin stays exactly on the vertex: the
// corrector's rays must lie on the lines of the chain (an origin pushed along the normal, as Scene::spawnRay
// does, would move the next vertex by up to 1e-4 and leave the path that far off the manifold), so
// self-intersection is avoided with tmin = the scene's offset length instead.
Ray chainRay(const Scene &scene, const Vec3 &origin, const Vec3 &d) { return Ray(origin, d, scene.epsilonAt(origin)); }

// Whether a constrained vertex keeps its configuration along a corrector trace: same shape and BSDF, hit from
// the same side, and an outgoing direction on the side its scattering type requires.
bool sameConfiguration(const ManifoldVertex &old, const Intersection &its, const Vec3 &wi) {
    if (its.shape != old.its.shape || its.bsdf() != old.its.bsdf()) return false;
    return (dot(wi, its.n) > 0) == old.predecessorAbove;
}

}  // namespace

bool intersectOpaque(const Scene &scene, Ray ray, Intersection &its) {
    for (int crossings = 0; crossings < kMaxCrossings; ++crossings) {
        if (!scene.intersect(ray, its)) return false;
        const BSDF *bsdf = its.bsdf();
        if (!bsdf || !bsdf->isNull()) return true;
        // Along the same line past the crossing (the ray's direction is a unit vector: t is a length).
        ray.tmin = its.t + scene.epsilonAt(its.p);
    }
    return true;
}

namespace {

size_t constrainedCount(const std::vector<ManifoldVertex> &chain) {
    return static_cast<size_t>(
        std::count_if(chain.begin(), chain.end(), [](const ManifoldVertex &v) { return v.isConstrained(); }));
}

}  // namespace

ManifoldWalk::ManifoldWalk(const Scene &scene, const ManifoldWalkParameters &params)
    : scene_(scene), params_(params), scale_(params.sceneScale) {
    if (!(scale_ > 0.0) && scene.bounds().valid()) scale_ = scene.bounds().extents().length();
    if (!(scale_ > 0.0) || !std::isfinite(scale_)) scale_ = 1.0;
}

std::optional<std::vector<ManifoldVertex>> ManifoldWalk::propagate(const std::vector<ManifoldVertex> &chain,
                                                                   const Vec3 &origin, const Vec3 &d,
                                                                   const ManifoldVertex *endPlane) const {
    const size_t k = chain.size();
    if (k < 2) return std::nullopt;
    std::vector<ManifoldVertex> out = chain;
    Vec3 rayOrigin = chain[0].p, dir = d;
    if (chain[0].type == ManifoldVertexType::FixedDirection) {
        out[0].p = rayOrigin = origin;
        dir = chain[0].ng;
    }
    for (size_t i = 1; i + 1 < k; ++i) {
        const ManifoldVertex &old = chain[i];
        if (old.type == ManifoldVertexType::Medium) {
            // [TR §7.1]: x'_i = x_{i-1} + |x_{i-1} - x_i| d, with no surface on the way but index-matched ones, then
            // the offset becomes the outgoing direction in the frame of the new incoming one.
            Intersection blocker;
            if (intersectOpaque(scene_, Ray(rayOrigin, dir, scene_.epsilonAt(rayOrigin), old.segment), blocker))
                return std::nullopt;
            ManifoldVertex v = old;
            v.p = rayOrigin + dir * old.segment;
            const std::optional<Vec3> wo = v.setIncoming(dir) ? microfacetNormal(v) : std::nullopt;
            if (!wo) return std::nullopt;
            out[i] = v;
            rayOrigin = v.p;
            dir = normalize(*wo);
            continue;
        }
        Intersection its;
        if (!intersectOpaque(scene_, chainRay(scene_, rayOrigin, dir), its)) return std::nullopt;
        const Vec3 wi = -dir;
        if (!sameConfiguration(old, its, wi)) return std::nullopt;
        std::optional<ManifoldVertex> v = ManifoldVertex::surface(its, old.scattering, old.eta);
        if (!v) return std::nullopt;
        v->offset = old.offset;
        v->glossy = old.glossy;
        v->halfVectorAbove = old.halfVectorAbove;
        v->predecessorAbove = old.predecessorAbove;
        const std::optional<Vec3> m = microfacetNormal(*v);
        if (!m) return std::nullopt;
        const std::optional<Vec3> wo = scatterAbout(wi, *m, old.scattering, old.eta);
        if (!wo) return std::nullopt;
        const bool woAbove = dot(*wo, its.n) > 0;
        if (woAbove != (old.scattering == Scattering::Reflection ? old.predecessorAbove : !old.predecessorAbove))
            return std::nullopt;
        out[i] = *v;
        rayOrigin = v->p;
        dir = normalize(*wo);
    }
    if (endPlane) {
        // The last segment ends on the virtual plane, whatever the scene holds there (§6.4).
        const double denom = dot(dir, endPlane->ng);
        const double t = dot(endPlane->p - rayOrigin, endPlane->ng) / denom;
        if (!(t > 0.0) || !std::isfinite(t)) return std::nullopt;
        out[k - 1] = *endPlane;
        out[k - 1].p = rayOrigin + dir * t;
        return out;
    }
    Intersection its;
    if (!intersectOpaque(scene_, chainRay(scene_, rayOrigin, dir), its)) return std::nullopt;
    std::optional<ManifoldVertex> end = ManifoldVertex::surface(its);
    if (!end) return std::nullopt;
    out[k - 1] = *end;
    return out;
}

WalkResult ManifoldWalk::walk(const std::vector<ManifoldVertex> &chain, const ManifoldVertex &target) const {
    WalkResult result;
    const size_t k = chain.size();
    ChainJacobian jacobian;
    result.stats.chainSize = static_cast<int>(constrainedCount(chain));
    if (k < 2 || (target.type != ManifoldVertexType::Surface && target.type != ManifoldVertexType::MediumEndpoint))
        return result;
    const std::optional<ManifoldVertex> plane = virtualPlane(chain[k - 1].p, chain[k - 1].ng, target.p, target.ng);
    if (!plane) return result;

    std::vector<ManifoldVertex> current = chain;
    current[k - 1] = *plane;
    const double tolerance = params_.epsilon * scale_;
    double beta = 1.0;
    double dist = (current[k - 1].p - target.p).length();
    // Without unknowns x_n is free (a plain edge): only the visibility check remains.
    const bool hasUnknowns = chain[0].type == ManifoldVertexType::FixedDirection || k > 2;
    while (hasUnknowns && dist > tolerance) {
        if (result.stats.iterations >= params_.maxIterations) {
            result.status = WalkStatus::IterationLimit;
            return result;
        }
        ++result.stats.iterations;
        if (!jacobian.build(current)) {
            if (jacobian.singular) {
                ++result.stats.singularJacobians;
                result.status = WalkStatus::SingularJacobian;
            }
            return result;
        }
        // Predictor: the first unknown moves by -β P_first A^{-1} B_n T(x_n)^T (x'_n - x_n) in its chart.
        const ManifoldVertex &end = current[k - 1];
        const Vec3 delta = target.p - end.p;
        const Vec2 endStep(dot(end.dpdu, delta), dot(end.dpdv, delta));
        const Vec2 step = jacobian.firstFromLast * endStep * -beta;
        const ManifoldVertex &first = current[jacobian.unknowns[0]];
        const Vec3 predicted = first.p + first.dpdu * step.x + first.dpdv * step.y;
        // Corrector: project back onto the manifold by tracing from the fixed end through the prediction.
        const Vec3 towards = predicted - current[0].p;
        const bool fixedDirection = jacobian.unknowns[0] == 0;
        const double towardsLength = towards.length();
        std::optional<std::vector<ManifoldVertex>> corrected;
        if (fixedDirection || towardsLength > 0.0)
            corrected =
                propagate(current, predicted, fixedDirection ? current[0].ng : towards / towardsLength, &*plane);
        const double newDist = corrected ? (corrected->back().p - target.p).length() : kInfinity;
        if (newDist < dist) {
            current = std::move(*corrected);
            dist = newDist;
            beta = std::min(1.0, 2.0 * beta);
        } else {
            beta *= 0.5;
        }
    }
    // The plane stood in for the real geometry at the end: x_{n-1} must see x'_n (§6.4).
    current[k - 1] = target;
    Intersection blocker;
    if (intersectOpaque(scene_, scene_.spawnRayTo(current[k - 2].p, target.p), blocker)) {
        result.status = WalkStatus::Occluded;
        return result;
    }
    result.status = WalkStatus::Converged;
    result.stats.converged = true;
    result.chain = std::move(current);
    return result;
}

}  // namespace pf
