// Mitsuba 0.6 "plastic": a diffuse base under a smooth dielectric coating. Light is either reflected
// specularly by the coating (Fresnel F_i) or refracted into it, scattered diffusely and refracted out,
// with the internal reflections at the coating summed in closed form:
//     f_diffuse = (1 - F_i) (1 - F_o) / eta^2 * rho / (pi (1 - F_dr))     (linear, Mitsuba's default)
//     f_diffuse = (1 - F_i) (1 - F_o) / eta^2 * rho / (pi (1 - rho F_dr))  ("nonlinear")
// where F_dr is the diffuse reflectance of the coating seen from inside. The model is one-sided and
// reciprocal. Sampling picks the specular lobe with probability proportional to F_i times the relative
// weight of the specular reflectance.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"
#include "core/warp.h"

namespace pf {

namespace {

class Plastic final : public BSDF {
public:
    Plastic(double eta, bool nonlinear, std::shared_ptr<Texture> specularReflectance,
            std::shared_ptr<Texture> diffuseReflectance)
        : eta_(eta),
          invEta2_(1.0 / (eta * eta)),
          fdrInt_(fresnelDiffuseReflectance(1.0 / eta)),
          nonlinear_(nonlinear),
          specularReflectance_(std::move(specularReflectance)),
          diffuseReflectance_(std::move(diffuseReflectance)) {
        const uint32_t varying = variationFlag(*specularReflectance_) | variationFlag(*diffuseReflectance_);
        flags_ = BSDFFlags::DeltaReflection | BSDFFlags::DiffuseReflection | BSDFFlags::FrontSide | varying;
        const double s = specularReflectance_->average().luminance(), d = diffuseReflectance_->average().luminance();
        specularSamplingWeight_ = s + d > 0 ? s / (s + d) : 0.5;
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (wi.z <= 0 || wo.z <= 0) return Spectrum(0.0);
        const double Fi = fresnelDielectric(wi.z, eta_);
        if (measure == Measure::Discrete) {
            if (!hasLobe(ctx, BSDFFlags::DeltaReflection) || !isMirrorPair(wi, wo)) return Spectrum(0.0);
            return specularReflectance_->eval(its) * Fi;
        }
        if (measure != Measure::SolidAngle || !hasLobe(ctx, BSDFFlags::DiffuseReflection)) return Spectrum(0.0);
        const double Fo = fresnelDielectric(wo.z, eta_);
        return diffuseAlbedo(its) * (kInvPi * wo.z * (1.0 - Fi) * (1.0 - Fo) * invEta2_);
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (wi.z <= 0 || wo.z <= 0) return 0.0;
        const double pSpec = specularProbability(ctx, wi);
        if (measure == Measure::Discrete)
            return hasLobe(ctx, BSDFFlags::DeltaReflection) && isMirrorPair(wi, wo) ? pSpec : 0.0;
        if (measure != Measure::SolidAngle || !hasLobe(ctx, BSDFFlags::DiffuseReflection)) return 0.0;
        return (1.0 - pSpec) * warp::squareToCosineHemispherePdf(wo);
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &u2) const override {
        const bool hasSpec = hasLobe(ctx, BSDFFlags::DeltaReflection);
        const bool hasDiff = hasLobe(ctx, BSDFFlags::DiffuseReflection);
        if ((!hasSpec && !hasDiff) || wi.z <= 0) return Spectrum(0.0);
        const double Fi = fresnelDielectric(wi.z, eta_);
        const double pSpec = specularProbability(ctx, wi);
        bs.eta = 1.0;
        if (u1 < pSpec) {
            bs.wo = reflect(wi);
            bs.pdf = pSpec;
            bs.sampledType = BSDFFlags::DeltaReflection;
            return specularReflectance_->eval(its) * (Fi / pSpec);
        }
        bs.wo = warp::squareToCosineHemisphere(u2);
        bs.pdf = (1.0 - pSpec) * warp::squareToCosineHemispherePdf(bs.wo);
        bs.sampledType = BSDFFlags::DiffuseReflection;
        if (bs.pdf == 0) return Spectrum(0.0);
        const double Fo = fresnelDielectric(bs.wo.z, eta_);
        return diffuseAlbedo(its) * ((1.0 - Fi) * (1.0 - Fo) * invEta2_ / (1.0 - pSpec));
    }

    Spectrum diffuseReflectance(const Intersection &its) const override { return diffuseReflectance_->eval(its); }

private:
    // Probability of choosing the specular lobe for wi (Mitsuba: F_i scaled by the sampling weight).
    double specularProbability(const BSDFContext &ctx, const Vec3 &wi) const {
        const bool hasSpec = hasLobe(ctx, BSDFFlags::DeltaReflection);
        const bool hasDiff = hasLobe(ctx, BSDFFlags::DiffuseReflection);
        if (!hasSpec || !hasDiff) return hasSpec ? 1.0 : 0.0;
        const double Fi = fresnelDielectric(wi.z, eta_);
        const double s = Fi * specularSamplingWeight_, d = (1.0 - Fi) * (1.0 - specularSamplingWeight_);
        return s + d > 0 ? s / (s + d) : 0.0;
    }
    // rho / (1 - F_dr) or rho / (1 - rho F_dr): the diffuse base including internal reflections.
    Spectrum diffuseAlbedo(const Intersection &its) const {
        const Spectrum rho = diffuseReflectance_->eval(its);
        if (!nonlinear_) return rho / (1.0 - fdrInt_);
        return rho / (Spectrum(1.0) - rho * fdrInt_);
    }

    double eta_, invEta2_, fdrInt_;
    bool nonlinear_;
    double specularSamplingWeight_;
    std::shared_ptr<Texture> specularReflectance_, diffuseReflectance_;
};

}  // namespace

std::shared_ptr<Object> createPlasticBSDF(const Properties &props, const LoadContext &) {
    const double intIOR = readDielectricIOR(props, "intIOR", "polypropylene");
    const double extIOR = readDielectricIOR(props, "extIOR", "air");
    const bool nonlinear = props.getBool("nonlinear", false);
    return std::make_shared<Plastic>(intIOR / extIOR, nonlinear,
                                     readUnitTexture(props, "specularReflectance", Spectrum(1.0)),
                                     readUnitTexture(props, "diffuseReflectance", Spectrum(0.5)));
}

}  // namespace pf
