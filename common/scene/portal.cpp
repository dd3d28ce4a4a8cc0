#include "scene/portal.h"

#include <cmath>

#include "core/transform.h"
#include "scene/properties.h"

namespace pf {

std::shared_ptr<Portal> Portal::fromProperties(const Properties &props) {
    if (!props.children(ObjectKind::BSDF).empty() || !props.children(ObjectKind::Emitter).empty() ||
        props.child(ObjectKind::Medium, "interior") || props.child(ObjectKind::Medium, "exterior"))
        props.fail("portal", "a portal is invisible and takes no BSDF, emitter or medium");
    const Transform toWorld = props.getTransform("toWorld", Transform());
    auto portal = std::make_shared<Portal>();
    portal->corner_ = toWorld.point(Vec3(-1, -1, 0));
    portal->du_ = toWorld.point(Vec3(1, -1, 0)) - portal->corner_;
    portal->dv_ = toWorld.point(Vec3(-1, 1, 0)) - portal->corner_;
    const Vec3 n = cross(portal->du_, portal->dv_);
    portal->area_ = n.length();
    // The loader refuses singular transforms; scales so small that the area underflows leave no opening
    // either (and no normal).
    if (!(portal->area_ > 0) || !std::isfinite(portal->area_))
        props.fail("toWorld", "a portal must have non-zero area (its transform collapses the rectangle)");
    const Vec3 z = toWorld.normal(Vec3(0, 0, 1));
    portal->n_ = n / portal->area_;
    if (dot(portal->n_, z) < 0) portal->n_ = -portal->n_;
    return portal;
}

double Portal::intersect(const Ray &ray) const {
    // The plane's parameter, then the hit's coordinates in the parallelogram's edge basis.
    const double denom = dot(ray.d, n_);
    if (denom == 0) return -1;
    const double t = dot(corner_ - ray.o, n_) / denom;
    if (!(t > ray.tmin && t < ray.tmax)) return -1;
    const Vec3 rel = ray(t) - corner_;
    const Vec3 nu = cross(dv_, n_), nv = cross(n_, du_);
    const double a = dot(rel, nu) / dot(du_, nu), b = dot(rel, nv) / dot(dv_, nv);
    return a >= 0 && a <= 1 && b >= 0 && b <= 1 ? t : -1;
}

}  // namespace pf
