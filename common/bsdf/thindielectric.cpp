// Mitsuba 0.6 "thindielectric": a thin slab of dielectric (window pane, soap film) whose two parallel
// boundaries are not resolved. Light is reflected specularly or passes straight through; the
// reflectance sums the geometric series of inter-reflections, R' = R + T^2 R / (1 - R^2). As in
// Mitsuba, the transmission lobe is a Null (index-matched) lobe: the ray continues undeflected, so
// shadow rays and integrators may pass through it.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"

namespace pf {

namespace {

class ThinDielectric final : public BSDF {
public:
    ThinDielectric(double eta, std::shared_ptr<Texture> specularReflectance,
                   std::shared_ptr<Texture> specularTransmittance)
        : eta_(eta),
          specularReflectance_(std::move(specularReflectance)),
          specularTransmittance_(std::move(specularTransmittance)) {
        flags_ = BSDFFlags::DeltaReflection | BSDFFlags::Null | BSDFFlags::FrontSide | BSDFFlags::BackSide |
                 variationFlag(*specularReflectance_) | variationFlag(*specularTransmittance_);
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (measure != Measure::Discrete) return Spectrum(0.0);
        const double R = slabReflectance(wi);
        if (wi.z * wo.z >= 0) {
            if (!hasLobe(ctx, BSDFFlags::DeltaReflection) || !isMirrorPair(wi, wo)) return Spectrum(0.0);
            return specularReflectance_->eval(its) * R;
        }
        if (!hasLobe(ctx, BSDFFlags::Null) || !isPassThrough(wi, wo)) return Spectrum(0.0);
        return specularTransmittance_->eval(its) * (1.0 - R);
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (measure != Measure::Discrete) return 0.0;
        const bool hasR = hasLobe(ctx, BSDFFlags::DeltaReflection), hasT = hasLobe(ctx, BSDFFlags::Null);
        const double R = slabReflectance(wi);
        if (wi.z * wo.z >= 0) {
            if (!hasR || !isMirrorPair(wi, wo)) return 0.0;
            return hasT ? R : 1.0;
        }
        if (!hasT || !isPassThrough(wi, wo)) return 0.0;
        return hasR ? 1.0 - R : 1.0;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &) const override {
        const bool hasR = hasLobe(ctx, BSDFFlags::DeltaReflection), hasT = hasLobe(ctx, BSDFFlags::Null);
        if (!hasR && !hasT) return Spectrum(0.0);
        const double R = slabReflectance(wi);
        bs.eta = 1.0;
        if (hasR && (!hasT || u1 < R)) {
            bs.wo = reflect(wi);
            bs.sampledType = BSDFFlags::DeltaReflection;
            bs.pdf = hasT ? R : 1.0;
            return specularReflectance_->eval(its) * (hasT ? 1.0 : R);
        }
        bs.wo = -wi;
        bs.sampledType = BSDFFlags::Null;
        bs.pdf = hasR ? 1.0 - R : 1.0;
        return specularTransmittance_->eval(its) * (hasR ? 1.0 : 1.0 - R);
    }

private:
    double slabReflectance(const Vec3 &wi) const {
        // The slab is symmetric, so the side the light arrives from does not matter.
        const double R = fresnelDielectric(std::abs(wi.z), eta_), T = 1.0 - R;
        return R < 1.0 ? R + T * T * R / (1.0 - R * R) : 1.0;
    }

    double eta_;
    std::shared_ptr<Texture> specularReflectance_, specularTransmittance_;
};

}  // namespace

std::shared_ptr<Object> createThinDielectricBSDF(const Properties &props, const LoadContext &) {
    const double intIOR = readDielectricIOR(props, "intIOR", "bk7");
    const double extIOR = readDielectricIOR(props, "extIOR", "air");
    return std::make_shared<ThinDielectric>(intIOR / extIOR,
                                            readUnitTexture(props, "specularReflectance", Spectrum(1.0)),
                                            readUnitTexture(props, "specularTransmittance", Spectrum(1.0)));
}

}  // namespace pf
