// Mitsuba 0.6 "roughconductor": the Cook-Torrance microfacet BRDF of a rough metal,
//     f(wi, wo) = F(wi . h) D(h) G(wi, wo, h) / (4 cos(theta_i) cos(theta_o)),   h = normalize(wi + wo)
// (Walter et al. 2007 eq. 20) with the exact conductor Fresnel term. Sampling picks a microfacet normal
// (all normals, or the visible ones) and reflects wi about it; the Jacobian dh/dwo = 1 / (4 |wo . h|)
// converts the normal density to a density of wo.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"
#include "bsdf/microfacet.h"

namespace pf {

namespace {

class RoughConductor final : public BSDF {
public:
    RoughConductor(MicrofacetParams microfacet, std::shared_ptr<Texture> specularReflectance, const ConductorIOR &ior)
        : microfacet_(std::move(microfacet)), specularReflectance_(std::move(specularReflectance)), ior_(ior) {
        flags_ = BSDFFlags::GlossyReflection | BSDFFlags::FrontSide | variationFlag(*specularReflectance_) |
                 (microfacet_.spatiallyVarying() ? BSDFFlags::SpatiallyVarying : 0u) |
                 (microfacet_.anisotropic() ? BSDFFlags::Anisotropic : 0u);
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (!active(ctx, wi, wo, measure)) return Spectrum(0.0);
        const Vec3 h = normalize(wi + wo);
        const MicrofacetDistribution distr = microfacet_.at(its);
        const double D = distr.eval(h);
        if (D == 0) return Spectrum(0.0);
        const double G = distr.G(wi, wo, h);
        return fresnel(its, wi, h) * (D * G / (4.0 * wi.z));
    }

    double pdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (!active(ctx, wi, wo, measure)) return 0.0;
        const Vec3 h = normalize(wi + wo);
        return microfacet_.at(its).pdf(wi, h) / (4.0 * std::abs(dot(wo, h)));
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double,
                    const Vec2 &u2) const override {
        if (!hasLobe(ctx, BSDFFlags::GlossyReflection) || wi.z <= 0) return Spectrum(0.0);
        const MicrofacetDistribution distr = microfacet_.at(its);
        double mPdf;
        const Vec3 m = distr.sample(wi, u2, mPdf);
        if (mPdf == 0) return Spectrum(0.0);
        bs.wo = reflect(wi, m);
        bs.eta = 1.0;
        bs.sampledType = BSDFFlags::GlossyReflection;
        if (bs.wo.z <= 0) return Spectrum(0.0);
        bs.pdf = mPdf / (4.0 * std::abs(dot(bs.wo, m)));
        // eval / pdf; with visible normals this reduces to F G1(wo, m) (Heitz & d'Eon 2014 eq. 17).
        const double weight = distr.sampleVisible()
                                  ? distr.G1(bs.wo, m)
                                  : distr.eval(m) * distr.G(wi, bs.wo, m) * dot(wi, m) / (mPdf * wi.z);
        return fresnel(its, wi, m) * weight;
    }

    double roughness(const Intersection &its, uint32_t lobe) const override {
        if (!(lobe & BSDFFlags::Glossy)) return BSDF::roughness(its, lobe);
        const MicrofacetDistribution distr = microfacet_.at(its);
        return 0.5 * (distr.alphaU() + distr.alphaV());  // Mitsuba's getRoughness
    }

private:
    static bool active(const BSDFContext &ctx, const Vec3 &wi, const Vec3 &wo, Measure measure) {
        return measure == Measure::SolidAngle && hasLobe(ctx, BSDFFlags::GlossyReflection) && wi.z > 0 && wo.z > 0;
    }
    Spectrum fresnel(const Intersection &its, const Vec3 &wi, const Vec3 &m) const {
        return specularReflectance_->eval(its) * fresnelConductor(dot(wi, m), ior_.eta, ior_.k);
    }

    MicrofacetParams microfacet_;
    std::shared_ptr<Texture> specularReflectance_;
    ConductorIOR ior_;
};

}  // namespace

std::shared_ptr<Object> createRoughConductorBSDF(const Properties &props, const LoadContext &) {
    MicrofacetParams microfacet = readMicrofacetParams(props, true);
    const ConductorIOR ior = readConductorIOR(props);
    return std::make_shared<RoughConductor>(std::move(microfacet),
                                            readUnitTexture(props, "specularReflectance", Spectrum(1.0)), ior);
}

}  // namespace pf
