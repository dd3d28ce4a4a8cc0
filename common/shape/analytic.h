// Analytic shapes (sphere, cylinder, disk) as Embree user geometry. Embree traverses its BVH in single
// precision, but the callbacks below intersect the surface in double precision against the original
// double ray of the query, which the Scene publishes for the calling thread while Embree runs (Embree
// calls user geometry synchronously on the thread that issued rtcIntersect1/rtcOccluded1).
#pragma once
#include <embree3/rtcore.h>

#include <limits>

#include "scene/shape.h"
#include "shape/shapegroup.h"

namespace pf {

// Makes `ray` the double-precision ray of this thread's Embree query for the object's lifetime. Queries
// issued without one (e.g. a benchmark calling rtcIntersect1 on Scene::embreeScene() directly) fall back
// to Embree's float ray.
class ScopedQueryRay {
public:
    explicit ScopedQueryRay(const Ray &ray);
    ~ScopedQueryRay();
    ScopedQueryRay(const ScopedQueryRay &) = delete;
    ScopedQueryRay &operator=(const ScopedQueryRay &) = delete;
};

// double -> float for Embree, saturating to +-infinity (a plain conversion of an out-of-range value is
// undefined behaviour).
inline float toEmbreeFloat(double v) {
    constexpr double kMax = std::numeric_limits<float>::max();
    return v > kMax ? std::numeric_limits<float>::infinity()
                    : (v < -kMax ? -std::numeric_limits<float>::infinity() : static_cast<float>(v));
}

class AnalyticShape : public Shape, public Instanceable {
public:
    unsigned addToEmbree(RTCDevice device, RTCScene scene) const override;
    size_t primitiveCount() const override { return 1; }
    // Nearest intersection distance in the open interval (tmin, tmax), in double precision.
    virtual bool intersectRay(const Ray &ray, double tmin, double tmax, double &t) const = 0;
};

// Solves a t^2 + 2 b t + c = 0 for its roots t0 <= t1 with the cancellation-free formulation of
// Haines et al., "Precision improvements for ray/sphere intersection" (Ray Tracing Gems, ch. 7): the
// discriminant b^2 - a c is passed in already computed from a well-conditioned expression.
bool solveQuadratic(double a, double b, double c, double discriminant, double &t0, double &t1);

}  // namespace pf
