// Exact Fresnel equations for smooth dielectric and conducting boundaries (unpolarized light), in the
// local frame of bsdf.h (normal = +z, the exterior on the +z side). pbrt-v3 §8.2 and Mitsuba 0.6's
// fresnelDielectricExt / fresnelConductorExact compute the same quantities.
#pragma once
#include "core/spectrum.h"
#include "core/vector.h"

namespace pf {

// Reflectance of a dielectric boundary with relative index eta = eta_interior / eta_exterior for light
// arriving with cosine cosThetaI (negative: from the interior side). cosThetaT receives the signed
// cosine of the refracted direction (opposite sign to cosThetaI), or 0 under total internal reflection
// (where the reflectance is 1).
double fresnelDielectric(double cosThetaI, double eta, double &cosThetaT);
double fresnelDielectric(double cosThetaI, double eta);

// Reflectance of a conductor with complex relative index eta + i k, per colour channel (exact, not
// Schlick; pbrt-v3 §8.2.1, "FrConductor"). For k = 0 it equals fresnelDielectric for cosThetaI > 0.
Spectrum fresnelConductor(double cosThetaI, const Spectrum &eta, const Spectrum &k);

// Diffuse Fresnel reflectance: the cosine-weighted hemispherical average 2 \int_0^1 F(mu, eta) mu dmu
// of fresnelDielectric for light arriving from the exterior (eta < 1 describes a boundary seen from
// the denser side). Integrated numerically to double precision; Mitsuba 0.6 uses a polynomial fit.
double fresnelDiffuseReflectance(double eta);

// Refraction of wi through a surface with normal m (wi and m need not share a hemisphere), given the
// signed cosine from fresnelDielectric(dot(wi, m), eta, cosThetaT). The result points away from the
// surface on the other side.
Vec3 refract(const Vec3 &wi, const Vec3 &m, double eta, double cosThetaT);
// The same about the shading normal (0, 0, 1).
inline Vec3 refract(const Vec3 &wi, double eta, double cosThetaT) {
    const double scale = cosThetaT < 0 ? 1.0 / eta : eta;
    return {-scale * wi.x, -scale * wi.y, cosThetaT};
}

}  // namespace pf
