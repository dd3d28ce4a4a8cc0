#include "shape/analytic.h"

#include <cmath>
#include <limits>

namespace pf {

namespace {

thread_local const Ray *tlQueryRay = nullptr;

Ray queryRay(RTCRayN *rays, unsigned n, unsigned i) {
    if (n == 1 && tlQueryRay) return *tlQueryRay;
    return Ray(Vec3(RTCRayN_org_x(rays, n, i), RTCRayN_org_y(rays, n, i), RTCRayN_org_z(rays, n, i)),
               Vec3(RTCRayN_dir_x(rays, n, i), RTCRayN_dir_y(rays, n, i), RTCRayN_dir_z(rays, n, i)),
               RTCRayN_tnear(rays, n, i), RTCRayN_tfar(rays, n, i));
}

void boundsCallback(const RTCBoundsFunctionArguments *args) {
    const AABB b = static_cast<const AnalyticShape *>(args->geometryUserPtr)->bbox();
    // Round outwards so that the float box contains the double one.
    constexpr float inf = std::numeric_limits<float>::infinity();
    args->bounds_o->lower_x = std::nextafter(toEmbreeFloat(b.min.x), -inf);
    args->bounds_o->lower_y = std::nextafter(toEmbreeFloat(b.min.y), -inf);
    args->bounds_o->lower_z = std::nextafter(toEmbreeFloat(b.min.z), -inf);
    args->bounds_o->upper_x = std::nextafter(toEmbreeFloat(b.max.x), inf);
    args->bounds_o->upper_y = std::nextafter(toEmbreeFloat(b.max.y), inf);
    args->bounds_o->upper_z = std::nextafter(toEmbreeFloat(b.max.z), inf);
}

void intersectCallback(const RTCIntersectFunctionNArguments *args) {
    const auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    RTCRayN *rays = RTCRayHitN_RayN(args->rayhit, args->N);
    RTCHitN *hits = RTCRayHitN_HitN(args->rayhit, args->N);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const Ray ray = queryRay(rays, args->N, i);
        float &tfar = RTCRayN_tfar(rays, args->N, i);
        double t;
        if (!shape->intersectRay(ray, ray.tmin, std::min(ray.tmax, static_cast<double>(tfar)), t)) continue;
        tfar = static_cast<float>(t);
        // The normal and (u, v) are recomputed in double by fillIntersection; Embree needs none of them.
        RTCHitN_Ng_x(hits, args->N, i) = 0.0f;
        RTCHitN_Ng_y(hits, args->N, i) = 0.0f;
        RTCHitN_Ng_z(hits, args->N, i) = 0.0f;
        RTCHitN_u(hits, args->N, i) = 0.0f;
        RTCHitN_v(hits, args->N, i) = 0.0f;
        RTCHitN_primID(hits, args->N, i) = args->primID;
        RTCHitN_geomID(hits, args->N, i) = args->geomID;
        RTCHitN_instID(hits, args->N, i, 0) = args->context->instID[0];
    }
}

void occludedCallback(const RTCOccludedFunctionNArguments *args) {
    const auto *shape = static_cast<const AnalyticShape *>(args->geometryUserPtr);
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const Ray ray = queryRay(args->ray, args->N, i);
        float &tfar = RTCRayN_tfar(args->ray, args->N, i);
        double t;
        // Embree's convention for an occluded ray.
        if (shape->intersectRay(ray, ray.tmin, std::min(ray.tmax, static_cast<double>(tfar)), t))
            tfar = -std::numeric_limits<float>::infinity();
    }
}

}  // namespace

ScopedQueryRay::ScopedQueryRay(const Ray &ray) { tlQueryRay = &ray; }
ScopedQueryRay::~ScopedQueryRay() { tlQueryRay = nullptr; }

unsigned AnalyticShape::addToEmbree(RTCDevice device, RTCScene scene) const {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geom, 1);
    rtcSetGeometryUserData(geom, const_cast<AnalyticShape *>(this));
    rtcSetGeometryBoundsFunction(geom, boundsCallback, nullptr);
    rtcSetGeometryIntersectFunction(geom, intersectCallback);
    rtcSetGeometryOccludedFunction(geom, occludedCallback);
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    return id;
}

bool solveQuadratic(double a, double b, double c, double discriminant, double &t0, double &t1) {
    if (!(a != 0) || !(discriminant >= 0)) return false;
    // q = -(b + sign(b) sqrt(disc)) never cancels; the roots are q / a and c / q.
    const double q = -(b + std::copysign(std::sqrt(discriminant), b));
    if (q == 0) {
        t0 = t1 = 0.0;  // b = disc = 0 implies c = 0: a double root at zero
        return true;
    }
    t0 = q / a;
    t1 = c / q;
    if (t0 > t1) std::swap(t0, t1);
    return std::isfinite(t0) && std::isfinite(t1);
}

}  // namespace pf
