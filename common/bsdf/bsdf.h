// BSDF interface (Mitsuba 0.6 conventions, so that Mitsuba scenes render the same):
// * all directions are in the local shading frame of the intersection, normal = +z, both pointing away
//   from the surface; wi is the direction the path arrived from, wo the one being sampled or evaluated;
// * eval() returns f(wi, wo) * |cos(theta_o)| (the cosine foreshortening w.r.t. the shading normal is
//   included);
// * for delta components, eval()/pdf() with Measure::Discrete give the discrete weight and probability;
// * the TransportMode says whether radiance (from the camera) or importance (from a light) is carried:
//   in Importance mode a BSDF returns the adjoint f*(wi, wo) = f(wo, wi), which differs from f for
//   refraction (the 1/eta^2 radiance scaling is dropped, Veach 1997 §5.2). The shading-normal part of
//   the adjoint (Veach 1997 §5.3, eq. 5.19) depends on the geometric normal and is applied by
//   shadingNormalCorrection() below, which bidirectional code multiplies in.
#pragma once
#include <cstdint>
#include <memory>

#include "core/spectrum.h"
#include "scene/intersection.h"
#include "scene/object.h"
#include "scene/records.h"

namespace pf {

enum class TransportMode { Radiance, Importance };

namespace BSDFFlags {
enum : uint32_t {
    Null = 1u << 0,  // index-matched pass-through (null, mask's transparent part)
    DiffuseReflection = 1u << 1,
    DiffuseTransmission = 1u << 2,
    GlossyReflection = 1u << 3,
    GlossyTransmission = 1u << 4,
    DeltaReflection = 1u << 5,
    DeltaTransmission = 1u << 6,
    FrontSide = 1u << 7,
    BackSide = 1u << 8,
    SpatiallyVarying = 1u << 9,
    Anisotropic = 1u << 10,

    Reflection = DiffuseReflection | GlossyReflection | DeltaReflection,
    Transmission = DiffuseTransmission | GlossyTransmission | DeltaTransmission | Null,
    Diffuse = DiffuseReflection | DiffuseTransmission,
    Glossy = GlossyReflection | GlossyTransmission,
    Smooth = Diffuse | Glossy,
    Delta = Null | DeltaReflection | DeltaTransmission,
    All = Diffuse | Glossy | Delta,
};
}

struct BSDFContext {
    TransportMode mode = TransportMode::Radiance;
    uint32_t typeMask = BSDFFlags::All;  // restrict to these lobes
    BSDFContext() = default;
    explicit BSDFContext(TransportMode m, uint32_t mask = BSDFFlags::All) : mode(m), typeMask(mask) {}
};

struct BSDFSample {
    Vec3 wo;                   // sampled direction, local shading frame
    double pdf = 0;            // solid-angle density, or discrete probability for delta lobes
    double eta = 1;            // relative index of refraction along the sampled direction (1 for reflection)
    uint32_t sampledType = 0;  // the BSDFFlags lobe that was sampled
};

class BSDF : public Object {
public:
    // f(wi, wo) |cos theta_o| for the given measure (SolidAngle for smooth lobes, Discrete for delta).
    virtual Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                          Measure measure = Measure::SolidAngle) const = 0;
    virtual double pdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                       Measure measure = Measure::SolidAngle) const = 0;
    // eval and pdf of one direction pair in one call (next-event estimation weighs its sample with both);
    // models whose two share their tests override it, saving the second dispatch (issue 17).
    virtual Spectrum evalPdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                             double &pdfOut) const {
        pdfOut = pdf(ctx, its, wi, wo);
        return eval(ctx, its, wi, wo);
    }
    // Samples wo given wi; returns eval/pdf (the sample weight), or zero on failure.
    // u2 drives the direction, u1 the choice between lobes.
    virtual Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                            const Vec2 &u2) const = 0;

    // Union of BSDFFlags over all lobes (for the whole surface, not a specific point).
    uint32_t flags() const { return flags_; }
    bool hasDelta() const { return (flags_ & BSDFFlags::Delta) != 0; }
    // True for surfaces through which light only passes without changing direction (the null BSDF,
    // which also bounds index-matched media).
    bool isNull() const { return (flags_ & BSDFFlags::All) == BSDFFlags::Null; }
    // Relative IOR interior/exterior (1 for non-refractive models).
    virtual double eta() const { return 1.0; }
    // Roughness (alpha) of the given lobe at its; 0 for delta lobes, infinity for diffuse.
    // Manifold exploration's glossy extension uses it (ALGORITHMS.md §6.6).
    virtual double roughness(const Intersection &its, uint32_t lobe) const;
    // Diffuse albedo, for display and for the dashboard's albedo preview.
    virtual Spectrum diffuseReflectance(const Intersection &its) const;

protected:
    uint32_t flags_ = 0;
};

// Veach's correction for shading normals in importance transport (Veach 1997, eq. 5.19): the factor
// |wi . Ng| |wo . Ns| / (|wi . Ns| |wo . Ng|) (world-space directions) by which the adjoint BSDF
// differs from the radiance BSDF when shading and geometric normals differ. Returns 0 when either
// direction lies in a different hemisphere w.r.t. geometric and shading normals (light leak).
double shadingNormalCorrection(const Intersection &its, const Vec3 &wiWorld, const Vec3 &woWorld);

}  // namespace pf
