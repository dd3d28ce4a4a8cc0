#include "bsdf/bsdf.h"

#include <cmath>

namespace pf {

double BSDF::roughness(const Intersection &, uint32_t lobe) const {
    // Delta lobes are perfectly sharp; everything else defaults to "as rough as diffuse". Glossy
    // models override this with their alpha.
    return (lobe & BSDFFlags::Delta) ? 0.0 : kInfinity;
}

Spectrum BSDF::diffuseReflectance(const Intersection &) const { return Spectrum(0.0); }

double shadingNormalCorrection(const Intersection &its, const Vec3 &wiWorld, const Vec3 &woWorld) {
    const double wiNg = dot(wiWorld, its.n), woNg = dot(woWorld, its.n);
    const double wiNs = dot(wiWorld, its.shFrame.n), woNs = dot(woWorld, its.shFrame.n);
    // A direction on different sides of the geometric and the shading normal would leak light
    // through the surface; such paths get no contribution.
    if (wiNg * wiNs <= 0 || woNg * woNs <= 0) return 0.0;
    return std::abs(wiNg * woNs) / std::abs(wiNs * woNg);
}

}  // namespace pf
