// Microfacet distributions shared by roughconductor, roughdielectric and roughplastic (Mitsuba 0.6's
// MicrofacetDistribution): Beckmann, GGX (Trowbridge-Reitz) and Phong (anisotropic: Ashikhmin-Shirley),
// each isotropic or anisotropic with roughness alphaU along the tangent and alphaV along the bitangent.
// Formulas follow Walter et al. 2007, "Microfacet Models for Refraction through Rough Surfaces", and
// Heitz 2014, "Understanding the Masking-Shadowing Function in Microfacet-Based BRDFs" (Smith G1 via
// Lambda, anisotropy by stretching). Normals are sampled either from D(m) cos(theta_m) ("all normals")
// or from the distribution of normals visible from wi (Heitz & d'Eon 2014, "Importance Sampling
// Microfacet-Based BSDFs using the Distribution of Visible Normals"), Mitsuba's sampleVisible switch.
#pragma once
#include <memory>
#include <string>

#include "core/vector.h"
#include "scene/intersection.h"
#include "scene/properties.h"

namespace pf {

class Texture;

enum class MicrofacetType { Beckmann, GGX, Phong };

class MicrofacetDistribution {
public:
    // Roughness below 1e-4 is clamped to it, as in Mitsuba (use the smooth models for zero roughness).
    // Phong has no visible-normal sampler (as in Mitsuba 0.6), so sampleVisible is ignored for it.
    MicrofacetDistribution(MicrofacetType type, double alphaU, double alphaV, bool sampleVisible);

    MicrofacetType type() const { return type_; }
    double alphaU() const { return alphaU_; }
    double alphaV() const { return alphaV_; }
    bool sampleVisible() const { return sampleVisible_; }
    bool isIsotropic() const { return alphaU_ == alphaV_; }

    // Scales both roughness values: Walter et al. 2007 (§5.3) widen the sampling lobe of rough
    // dielectrics by 1.2 - 0.2 sqrt(|cos theta_i|) to tame the weights when sampling all normals.
    void scaleAlpha(double s);

    // Normal distribution D(m) per unit solid angle of m (zero below the surface); D(m) cos(theta_m)
    // integrates to one over the hemisphere.
    double eval(const Vec3 &m) const;
    // Smith's masking function G1(v, m) (zero when v sees the back of the microfacet), exact for
    // Beckmann, GGX and isotropic Phong; anisotropic Phong (Ashikhmin-Shirley, not stretch-invariant)
    // uses the isotropic function at the exponent interpolated along v's azimuth, as Mitsuba does for
    // its roughness.
    double G1(const Vec3 &v, const Vec3 &m) const;
    // Separable masking-shadowing G1(wi, m) G1(wo, m), as Mitsuba 0.6.
    double G(const Vec3 &wi, const Vec3 &wo, const Vec3 &m) const { return G1(wi, m) * G1(wo, m); }

    // Samples a microfacet normal for wi (which must have cos theta > 0) and returns it with its
    // solid-angle density; pdf() gives the same density for any m.
    Vec3 sample(const Vec3 &wi, const Vec2 &u, double &pdf) const;
    double pdf(const Vec3 &wi, const Vec3 &m) const;

private:
    double projectedAlpha(const Vec3 &v) const;
    double phongExponent(const Vec3 &m) const;
    // Azimuth of the normal for the anisotropic all-normals samplers, and 1 / alpha^2 along it.
    double sampleAzimuth(double u, double &invAlphaSqr) const;
    Vec3 sampleAll(const Vec2 &u, double &pdf) const;
    Vec3 sampleVisibleNormal(const Vec3 &wi, const Vec2 &u) const;

    MicrofacetType type_;
    double alphaU_, alphaV_;
    bool sampleVisible_;
    double exponentU_ = 0, exponentV_ = 0;  // Phong exponents 2 / alpha^2 - 2
};

// The microfacet parameters of Mitsuba 0.6's rough plugins: distribution ("beckmann", "ggx", "phong",
// or "as", which Mitsuba 0.6 treats as an alias of the anisotropic Phong model), alpha or alphaU/alphaV
// (floats or textures, default 0.1) and sampleVisible (default true).
struct MicrofacetParams {
    MicrofacetType type = MicrofacetType::Beckmann;
    std::shared_ptr<Texture> alphaU, alphaV;  // the same texture when isotropic
    bool sampleVisible = true;

    bool anisotropic() const { return alphaU != alphaV; }
    bool spatiallyVarying() const;
    // The distribution at a surface point (textured roughness is averaged over colour channels).
    MicrofacetDistribution at(const Intersection &its) const;
};

// Reads and validates the parameters above; allowAnisotropic = false rejects alphaU/alphaV (plugins
// that, like Mitsuba's roughplastic, only support isotropic roughness).
MicrofacetParams readMicrofacetParams(const Properties &props, bool allowAnisotropic);

}  // namespace pf
