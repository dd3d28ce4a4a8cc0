// Mitsuba 0.6 "diffuse": the one-sided Lambertian BRDF f = reflectance / pi, cosine-weighted sampling.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "core/warp.h"

namespace pf {

namespace {

class Diffuse final : public BSDF {
public:
    explicit Diffuse(std::shared_ptr<Texture> reflectance) : reflectance_(std::move(reflectance)) {
        flags_ = BSDFFlags::DiffuseReflection | BSDFFlags::FrontSide | variationFlag(*reflectance_);
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (!active(ctx, wi, wo, measure)) return Spectrum(0.0);
        return reflectance_->eval(its) * (kInvPi * wo.z);
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        return active(ctx, wi, wo, measure) ? warp::squareToCosineHemispherePdf(wo) : 0.0;
    }

    Spectrum evalPdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                     double &pdfOut) const override {
        if (!active(ctx, wi, wo, Measure::SolidAngle)) {
            pdfOut = 0;
            return Spectrum(0.0);
        }
        pdfOut = warp::squareToCosineHemispherePdf(wo);
        return reflectance_->eval(its) * (kInvPi * wo.z);
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double,
                    const Vec2 &u2) const override {
        if (!hasLobe(ctx, BSDFFlags::DiffuseReflection) || wi.z <= 0) return Spectrum(0.0);
        bs.wo = warp::squareToCosineHemisphere(u2);
        bs.pdf = warp::squareToCosineHemispherePdf(bs.wo);
        bs.eta = 1.0;
        bs.sampledType = BSDFFlags::DiffuseReflection;
        if (bs.pdf == 0) return Spectrum(0.0);
        // f cos / pdf = (reflectance / pi) cos / (cos / pi).
        return reflectance_->eval(its);
    }

    Spectrum diffuseReflectance(const Intersection &its) const override { return reflectance_->eval(its); }

private:
    static bool active(const BSDFContext &ctx, const Vec3 &wi, const Vec3 &wo, Measure measure) {
        return measure == Measure::SolidAngle && hasLobe(ctx, BSDFFlags::DiffuseReflection) && wi.z > 0 && wo.z > 0;
    }

    std::shared_ptr<Texture> reflectance_;
};

}  // namespace

std::shared_ptr<Object> createDiffuseBSDF(const Properties &props, const LoadContext &) {
    // Mitsuba accepts "diffuseReflectance" as a synonym, for compatibility with the other models.
    const char *name = hasParameter(props, "reflectance") || !hasParameter(props, "diffuseReflectance")
                           ? "reflectance"
                           : "diffuseReflectance";
    return std::make_shared<Diffuse>(readUnitTexture(props, name, Spectrum(0.5)));
}

}  // namespace pf
