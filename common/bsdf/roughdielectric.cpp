// Mitsuba 0.6 "roughdielectric": reflection and refraction at a rough dielectric boundary (Walter et
// al. 2007). With eta the relative index across the boundary in the direction of wo, the generalized
// half vector is h = normalize(wi + eta wo) (eq. 16), and
//     reflection:   F D G / (4 |cos theta_i| |cos theta_o|)                                 (eq. 20)
//     transmission: |wi.h| |wo.h| eta^2 (1 - F) D G / (|cos theta_i| |cos theta_o| (wi.h + eta wo.h)^2)  (eq. 21)
// Eq. 21 is written for light travelling from wi to wo, i.e. it is the Importance-mode BSDF here; in
// Radiance mode the value is divided by eta^2, Mitsuba's "missing term" for the solid-angle compression
// of radiance (Veach 1997 §5.2), so that the two modes are adjoint. Both sides of the surface are
// active; the normal distribution is always evaluated in the hemisphere of the macro normal.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"
#include "bsdf/microfacet.h"

namespace pf {

namespace {

class RoughDielectric final : public BSDF {
public:
    RoughDielectric(double eta, MicrofacetParams microfacet, std::shared_ptr<Texture> specularReflectance,
                    std::shared_ptr<Texture> specularTransmittance)
        : eta_(eta),
          microfacet_(std::move(microfacet)),
          specularReflectance_(std::move(specularReflectance)),
          specularTransmittance_(std::move(specularTransmittance)) {
        flags_ = BSDFFlags::GlossyReflection | BSDFFlags::GlossyTransmission | BSDFFlags::FrontSide |
                 BSDFFlags::BackSide | variationFlag(*specularReflectance_) | variationFlag(*specularTransmittance_) |
                 (microfacet_.spatiallyVarying() ? BSDFFlags::SpatiallyVarying : 0u) |
                 (microfacet_.anisotropic() ? BSDFFlags::Anisotropic : 0u);
    }

    double eta() const override { return eta_; }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (measure != Measure::SolidAngle || wi.z == 0) return Spectrum(0.0);
        const bool reflection = wi.z * wo.z > 0;
        if (!hasLobe(ctx, reflection ? BSDFFlags::GlossyReflection : BSDFFlags::GlossyTransmission))
            return Spectrum(0.0);
        const double eta = reflection ? 1.0 : relativeEta(wi);
        const Vec3 h = halfVector(wi, wo, eta);
        const MicrofacetDistribution distr = microfacet_.at(its);
        const double D = distr.eval(h);
        if (D == 0) return Spectrum(0.0);
        const double F = fresnelDielectric(dot(wi, h), eta_);
        const double G = distr.G(wi, wo, h);
        if (reflection) return specularReflectance_->eval(its) * (F * D * G / (4.0 * std::abs(wi.z)));
        const double denom = dot(wi, h) + eta * dot(wo, h);
        const double value = (1.0 - F) * D * G * eta * eta * dot(wi, h) * dot(wo, h) / (wi.z * denom * denom);
        return specularTransmittance_->eval(its) * std::abs(value * radianceScale(ctx, eta));
    }

    double pdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (measure != Measure::SolidAngle || wi.z == 0) return 0.0;
        const bool hasR = hasLobe(ctx, BSDFFlags::GlossyReflection), hasT = hasLobe(ctx, BSDFFlags::GlossyTransmission);
        const bool reflection = wi.z * wo.z > 0;
        if (!(reflection ? hasR : hasT)) return 0.0;
        const double eta = reflection ? 1.0 : relativeEta(wi);
        const Vec3 h = halfVector(wi, wo, eta);
        // Both directions must see the front of the microfacet, as eval()'s masking term and sample()
        // require; Mitsuba 0.6 omits this test (Mitsuba 3 adds it), which gives density to pairs
        // that are never sampled.
        if (dot(wi, h) * wi.z <= 0 || dot(wo, h) * wo.z <= 0) return 0.0;
        double jacobian;  // |d omega_h / d omega_o| (Walter et al. 2007 eqs. 14 and 17)
        if (reflection) {
            jacobian = 1.0 / (4.0 * std::abs(dot(wo, h)));
        } else {
            const double denom = dot(wi, h) + eta * dot(wo, h);
            jacobian = eta * eta * std::abs(dot(wo, h)) / (denom * denom);
        }
        double prob = samplingDistribution(its, wi).pdf(wi.z > 0 ? wi : -wi, h);
        if (hasR && hasT) {
            const double F = fresnelDielectric(dot(wi, h), eta_);
            prob *= reflection ? F : 1.0 - F;
        }
        return prob * jacobian;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &u2) const override {
        const bool hasR = hasLobe(ctx, BSDFFlags::GlossyReflection), hasT = hasLobe(ctx, BSDFFlags::GlossyTransmission);
        if ((!hasR && !hasT) || wi.z == 0) return Spectrum(0.0);
        const MicrofacetDistribution distr = microfacet_.at(its);
        const MicrofacetDistribution sampler = samplingDistribution(its, wi);
        double mPdf;
        const Vec3 m = sampler.sample(wi.z > 0 ? wi : -wi, u2, mPdf);
        if (mPdf == 0) return Spectrum(0.0);
        double cosThetaT;
        const double F = fresnelDielectric(dot(wi, m), eta_, cosThetaT);

        // The lobe is chosen with probability F (reflection) or 1 - F, which then cancels from the
        // weight; with a single lobe enabled its Fresnel factor stays in the weight.
        const bool reflection = hasR && (!hasT || u1 < F);
        Spectrum weight(1.0);
        bs.pdf = mPdf;
        if (hasR && hasT)
            bs.pdf *= reflection ? F : 1.0 - F;
        else
            weight *= reflection ? F : 1.0 - F;

        double jacobian;
        if (reflection) {
            bs.wo = reflect(wi, m);
            bs.eta = 1.0;
            bs.sampledType = BSDFFlags::GlossyReflection;
            if (wi.z * bs.wo.z <= 0) return Spectrum(0.0);
            weight *= specularReflectance_->eval(its);
            jacobian = 1.0 / (4.0 * std::abs(dot(bs.wo, m)));
        } else {
            if (cosThetaT == 0) return Spectrum(0.0);
            bs.wo = refract(wi, m, eta_, cosThetaT);
            bs.eta = cosThetaT < 0 ? eta_ : 1.0 / eta_;
            bs.sampledType = BSDFFlags::GlossyTransmission;
            if (wi.z * bs.wo.z >= 0) return Spectrum(0.0);
            weight *= specularTransmittance_->eval(its) * radianceScale(ctx, bs.eta);
            const double denom = dot(wi, m) + bs.eta * dot(bs.wo, m);
            jacobian = bs.eta * bs.eta * std::abs(dot(bs.wo, m)) / (denom * denom);
        }
        // The remaining factor of eval / pdf: G1(wo, m) for visible normals (the rest cancels),
        // D G |wi.m| / (pdf(m) |cos theta_i|) in general.
        weight *= sampler.sampleVisible()
                      ? distr.G1(bs.wo, m)
                      : std::abs(distr.eval(m) * distr.G(wi, bs.wo, m) * dot(wi, m) / (mPdf * wi.z));
        bs.pdf *= jacobian;
        return weight;
    }

    double roughness(const Intersection &its, uint32_t lobe) const override {
        if (!(lobe & BSDFFlags::Glossy)) return BSDF::roughness(its, lobe);
        const MicrofacetDistribution distr = microfacet_.at(its);
        return 0.5 * (distr.alphaU() + distr.alphaV());
    }

private:
    // eta_o / eta_i for a refraction of wi.
    double relativeEta(const Vec3 &wi) const { return wi.z > 0 ? eta_ : 1.0 / eta_; }
    // The (generalized) half vector, oriented along the macro normal.
    static Vec3 halfVector(const Vec3 &wi, const Vec3 &wo, double eta) {
        const Vec3 h = normalize(wi + wo * eta);
        return h.z < 0 ? -h : h;
    }
    // Radiance is divided by eta^2 = (eta_o / eta_i)^2 when it crosses into wi's side.
    static double radianceScale(const BSDFContext &ctx, double eta) {
        return ctx.mode == TransportMode::Radiance ? 1.0 / (eta * eta) : 1.0;
    }
    // Sampling all normals uses Walter et al.'s widened lobe (§5.3, as Mitsuba); visible normals need
    // no such help.
    MicrofacetDistribution samplingDistribution(const Intersection &its, const Vec3 &wi) const {
        MicrofacetDistribution d = microfacet_.at(its);
        if (!d.sampleVisible()) d.scaleAlpha(1.2 - 0.2 * std::sqrt(std::abs(wi.z)));
        return d;
    }

    double eta_;
    MicrofacetParams microfacet_;
    std::shared_ptr<Texture> specularReflectance_, specularTransmittance_;
};

}  // namespace

std::shared_ptr<Object> createRoughDielectricBSDF(const Properties &props, const LoadContext &) {
    MicrofacetParams microfacet = readMicrofacetParams(props, true);
    const double intIOR = readDielectricIOR(props, "intIOR", "bk7");
    const double extIOR = readDielectricIOR(props, "extIOR", "air");
    return std::make_shared<RoughDielectric>(intIOR / extIOR, std::move(microfacet),
                                             readUnitTexture(props, "specularReflectance", Spectrum(1.0)),
                                             readUnitTexture(props, "specularTransmittance", Spectrum(1.0)));
}

}  // namespace pf
