// Mitsuba 0.6 "conductor": a smooth metal, an ideal mirror weighted by the exact conductor Fresnel
// reflectance of the complex index eta + i k (one-sided, like Mitsuba's).
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"

namespace pf {

namespace {

class Conductor final : public BSDF {
public:
    Conductor(std::shared_ptr<Texture> specularReflectance, const ConductorIOR &ior)
        : specularReflectance_(std::move(specularReflectance)), ior_(ior) {
        flags_ = BSDFFlags::DeltaReflection | BSDFFlags::FrontSide | variationFlag(*specularReflectance_);
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (!active(ctx, wi, wo, measure)) return Spectrum(0.0);
        return reflectance(its, wi);
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        return active(ctx, wi, wo, measure) ? 1.0 : 0.0;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double,
                    const Vec2 &) const override {
        if (!hasLobe(ctx, BSDFFlags::DeltaReflection) || wi.z <= 0) return Spectrum(0.0);
        bs.wo = reflect(wi);
        bs.pdf = 1.0;
        bs.eta = 1.0;
        bs.sampledType = BSDFFlags::DeltaReflection;
        return reflectance(its, wi);
    }

private:
    static bool active(const BSDFContext &ctx, const Vec3 &wi, const Vec3 &wo, Measure measure) {
        return measure == Measure::Discrete && hasLobe(ctx, BSDFFlags::DeltaReflection) && wi.z > 0 && wo.z > 0 &&
               isMirrorPair(wi, wo);
    }
    Spectrum reflectance(const Intersection &its, const Vec3 &wi) const {
        return specularReflectance_->eval(its) * fresnelConductor(wi.z, ior_.eta, ior_.k);
    }

    std::shared_ptr<Texture> specularReflectance_;
    ConductorIOR ior_;
};

}  // namespace

std::shared_ptr<Object> createConductorBSDF(const Properties &props, const LoadContext &) {
    const ConductorIOR ior = readConductorIOR(props);
    return std::make_shared<Conductor>(readUnitTexture(props, "specularReflectance", Spectrum(1.0)), ior);
}

}  // namespace pf
