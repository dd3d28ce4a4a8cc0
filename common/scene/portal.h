// Portals of the portal-based path perturbation (Otsu, Hanika & Dachsbacher, "Portal-Based Path
// Perturbation for Metropolis Light Transport", §4.3; ALGORITHMS.md §7.2): user-placed rectangles at the
// openings light passes through. They are not part of the scene's geometry: rays, shadow rays and every
// integrator other than the portal perturbation (path/portal_perturbation.h) do not see them.
//
// In the scene file a portal is a top-level `rectangle` shape with <boolean name="portal" value="true"/>
// and its toWorld transform (several may be given); it takes no BSDF, emitter or media.
#pragma once
#include <memory>

#include "core/vector.h"
#include "scene/object.h"

namespace pf {

class Properties;

class Portal final : public Object {
public:
    // The image of Mitsuba's rectangle [-1, 1]^2 x {0} under the properties' toWorld: a parallelogram
    // (see README on sheared rectangles). Zero area is an error naming the transform's line.
    static std::shared_ptr<Portal> fromProperties(const Properties &props);

    // The ray parameter t in (tmin, tmax) at which the ray crosses the portal (either side), or a
    // negative number when it does not.
    double intersect(const Ray &ray) const;
    // The unit normal of the portal's plane (the side toWorld maps +z to).
    const Vec3 &normal() const { return n_; }
    double area() const { return area_; }

private:
    Vec3 corner_, du_, dv_, n_;
    double area_ = 0;
};

}  // namespace pf
