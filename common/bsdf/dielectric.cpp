// Mitsuba 0.6 "dielectric": a smooth boundary between two dielectrics (glass, water), with ideal
// specular reflection and refraction weighted by the exact Fresnel equations. Both sides are active:
// wi below the surface means arriving from the interior.
//
// Radiance crossing the boundary is scaled by (eta_t / eta_i)^2 (Veach 1997 §5.2); in Mitsuba's
// convention that is a factor 1 / eta^2 in Radiance mode when wi lies outside (eta = interior /
// exterior), and eta^2 when wi lies inside. Importance is not scaled, which makes the Importance-mode
// BSDF the adjoint of the Radiance-mode one.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"

namespace pf {

namespace {

class Dielectric final : public BSDF {
public:
    Dielectric(double eta, std::shared_ptr<Texture> specularReflectance, std::shared_ptr<Texture> specularTransmittance)
        : eta_(eta),
          specularReflectance_(std::move(specularReflectance)),
          specularTransmittance_(std::move(specularTransmittance)) {
        const uint32_t sides = BSDFFlags::FrontSide | BSDFFlags::BackSide;
        flags_ = BSDFFlags::DeltaReflection | BSDFFlags::DeltaTransmission | sides |
                 variationFlag(*specularReflectance_) | variationFlag(*specularTransmittance_);
    }

    double eta() const override { return eta_; }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (measure != Measure::Discrete) return Spectrum(0.0);
        double cosThetaT;
        const double F = fresnelDielectric(wi.z, eta_, cosThetaT);
        if (wi.z * wo.z >= 0) {
            if (!hasLobe(ctx, BSDFFlags::DeltaReflection) || !isMirrorPair(wi, wo)) return Spectrum(0.0);
            return specularReflectance_->eval(its) * F;
        }
        if (!hasLobe(ctx, BSDFFlags::DeltaTransmission) || !sameDirection(refract(wi, eta_, cosThetaT), wo))
            return Spectrum(0.0);
        return specularTransmittance_->eval(its) * ((1.0 - F) * radianceScale(ctx, cosThetaT));
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (measure != Measure::Discrete) return 0.0;
        const bool hasR = hasLobe(ctx, BSDFFlags::DeltaReflection), hasT = hasLobe(ctx, BSDFFlags::DeltaTransmission);
        double cosThetaT;
        const double F = fresnelDielectric(wi.z, eta_, cosThetaT);
        if (wi.z * wo.z >= 0) {
            if (!hasR || !isMirrorPair(wi, wo)) return 0.0;
            return hasT ? F : 1.0;
        }
        if (!hasT || !sameDirection(refract(wi, eta_, cosThetaT), wo)) return 0.0;
        return hasR ? 1.0 - F : 1.0;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &) const override {
        const bool hasR = hasLobe(ctx, BSDFFlags::DeltaReflection), hasT = hasLobe(ctx, BSDFFlags::DeltaTransmission);
        if (!hasR && !hasT) return Spectrum(0.0);
        double cosThetaT;
        const double F = fresnelDielectric(wi.z, eta_, cosThetaT);
        // With both lobes the Fresnel term is the lobe probability and cancels from the weight.
        const bool chooseReflection = hasR && (!hasT || u1 < F);
        if (chooseReflection) {
            bs.wo = reflect(wi);
            bs.eta = 1.0;
            bs.sampledType = BSDFFlags::DeltaReflection;
            bs.pdf = hasT ? F : 1.0;
            return specularReflectance_->eval(its) * (hasT ? 1.0 : F);
        }
        bs.wo = refract(wi, eta_, cosThetaT);
        bs.eta = cosThetaT < 0 ? eta_ : 1.0 / eta_;
        bs.sampledType = BSDFFlags::DeltaTransmission;
        bs.pdf = hasR ? 1.0 - F : 1.0;
        if (cosThetaT == 0) return Spectrum(0.0);  // total internal reflection: nothing is transmitted
        return specularTransmittance_->eval(its) * ((hasR ? 1.0 : 1.0 - F) * radianceScale(ctx, cosThetaT));
    }

private:
    double radianceScale(const BSDFContext &ctx, double cosThetaT) const {
        if (ctx.mode == TransportMode::Importance) return 1.0;
        const double s = cosThetaT < 0 ? 1.0 / eta_ : eta_;
        return s * s;
    }

    double eta_;
    std::shared_ptr<Texture> specularReflectance_, specularTransmittance_;
};

}  // namespace

std::shared_ptr<Object> createDielectricBSDF(const Properties &props, const LoadContext &) {
    const double intIOR = readDielectricIOR(props, "intIOR", "bk7");
    const double extIOR = readDielectricIOR(props, "extIOR", "air");
    return std::make_shared<Dielectric>(intIOR / extIOR, readUnitTexture(props, "specularReflectance", Spectrum(1.0)),
                                        readUnitTexture(props, "specularTransmittance", Spectrum(1.0)));
}

}  // namespace pf
