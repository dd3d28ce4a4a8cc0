// Mitsuba 0.6 "roughplastic": a diffuse base under a rough dielectric coating (Weidlich & Wilkie 2007,
// as implemented by Mitsuba). The coating reflects with the microfacet BRDF of roughconductor but a
// dielectric Fresnel term; the base is seen through it:
//     f = F(wi.h) D G / (4 cos_i cos_o) + T(cos_i) T(cos_o) / eta^2 * rho / (pi (1 - F_dr))
// (or rho / (pi (1 - rho F_dr)) with "nonlinear"). T(cos) is the total transmittance of the rough
// interface for light arriving from outside at that angle: the energy the roughdielectric
// transmission lobe lets through, Smith masking included. Mitsuba reads T from tables precomputed
// offline (data/microfacet/*.dat); here it is integrated at construction over the microfacet normals
// for the actual (distribution, alpha, eta), tabulated in cos theta and shared between instances.
// F_dr, the coating's reflectance for diffuse light from inside, follows from T by reciprocity:
// 1 - F_dr = (1 / eta^2) \int T(mu) 2 mu dmu, which also makes a white base conserve energy exactly.
#include <map>
#include <mutex>
#include <tuple>
#include <vector>

#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"
#include "bsdf/fresnel.h"
#include "bsdf/ior.h"
#include "bsdf/microfacet.h"
#include "bsdf/quadrature.h"
#include "core/warp.h"

namespace pf {

namespace {

// T(cos theta) on nodes uniform in sqrt(cos theta) (T varies fastest near grazing), interpolated with
// Catmull-Rom splines.
class CoatingTransmittance {
public:
    CoatingTransmittance(const MicrofacetDistribution &visible, double eta) {
        // The integrand below is smooth with either sampler; sampling all normals is analytic and
        // therefore cheaper than the visible-normal inversion.
        const MicrofacetDistribution distr(visible.type(), visible.alphaU(), visible.alphaV(), false);
        values_.resize(kNodes);
        for (int j = 0; j < kNodes; ++j) {
            const double t = static_cast<double>(j) / (kNodes - 1);
            // The table starts just above grazing incidence, where the integrand's 1/cos is finite.
            values_[j] = integrate(distr, eta, std::max(t * t, 1e-6));
        }
        // \int_0^1 T(mu) 2 mu dmu = \int_0^1 T(t^2) 4 t^3 dt; the rule is exact per spline segment.
        diffuse_ = integrateUnitInterval([&](double t) { return eval(t * t) * 4.0 * t * t * t; }, kNodes - 1);
    }

    double eval(double cosTheta) const {
        const double x = std::sqrt(clamp(cosTheta, 0.0, 1.0)) * (kNodes - 1);
        const int i = std::min(static_cast<int>(x), kNodes - 2);
        const double f = x - i;
        const double p1 = values_[i], p2 = values_[i + 1];
        const double p0 = i > 0 ? values_[i - 1] : 2.0 * p1 - p2;
        const double p3 = i + 2 < kNodes ? values_[i + 2] : 2.0 * p2 - p1;
        const double v =
            p1 + 0.5 * f * (p2 - p0 + f * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + f * (3.0 * (p1 - p2) + p3 - p0)));
        return clamp(v, 0.0, 1.0);
    }
    double diffuse() const { return diffuse_; }

private:
    static constexpr int kNodes = 65;
    static constexpr int kPanels = 4;  // per dimension of the normal-sampling domain

    // \int f_t(wi, wo) |cos theta_o| dwo = \int (1 - F) D G |wi.m| / |cos theta_i| dm (Walter et al.
    // 2007 eqs. 17 and 21 with the Importance-mode eta^2), integrated over the sampler's unit square.
    static double integrate(const MicrofacetDistribution &distr, double eta, double mu) {
        const Vec3 wi(std::sqrt(1.0 - mu * mu), 0.0, mu);
        double sum = 0.0;
        forEachGaussLegendreNode(kPanels, [&](double u1, double w1) {
            forEachGaussLegendreNode(kPanels, [&](double u2, double w2) {
                double pdf;
                const Vec3 m = distr.sample(wi, Vec2(u1, u2), pdf);
                if (!(pdf > 0)) return;
                double cosThetaT;
                const double F = fresnelDielectric(dot(wi, m), eta, cosThetaT);
                if (cosThetaT == 0) return;
                const Vec3 wo = refract(wi, m, eta, cosThetaT);
                if (wo.z >= 0) return;
                sum += w1 * w2 * (1.0 - F) * distr.eval(m) * distr.G(wi, wo, m) * std::abs(dot(wi, m)) / (mu * pdf);
            });
        });
        return sum;
    }

    std::vector<double> values_;
    double diffuse_ = 0;
};

// Tables depend only on (distribution, alpha, eta), and scenes often repeat materials.
std::shared_ptr<const CoatingTransmittance> coatingTransmittance(const MicrofacetDistribution &distr, double eta) {
    using Key = std::tuple<int, double, double>;
    static std::mutex mutex;
    static std::map<Key, std::shared_ptr<const CoatingTransmittance>> cache;
    const Key key(static_cast<int>(distr.type()), distr.alphaU(), eta);
    std::lock_guard<std::mutex> lock(mutex);
    auto &entry = cache[key];
    if (!entry) entry = std::make_shared<const CoatingTransmittance>(distr, eta);
    return entry;
}

class RoughPlastic final : public BSDF {
public:
    RoughPlastic(const MicrofacetDistribution &distr, double eta, bool nonlinear,
                 std::shared_ptr<Texture> specularReflectance, std::shared_ptr<Texture> diffuseReflectance)
        : distr_(distr),
          eta_(eta),
          invEta2_(1.0 / (eta * eta)),
          nonlinear_(nonlinear),
          transmittance_(coatingTransmittance(distr, eta)),
          specularReflectance_(std::move(specularReflectance)),
          diffuseReflectance_(std::move(diffuseReflectance)) {
        fdrInt_ = 1.0 - transmittance_->diffuse() * invEta2_;
        const uint32_t varying = variationFlag(*specularReflectance_) | variationFlag(*diffuseReflectance_);
        flags_ = BSDFFlags::GlossyReflection | BSDFFlags::DiffuseReflection | BSDFFlags::FrontSide | varying;
        const double s = specularReflectance_->average().luminance(), d = diffuseReflectance_->average().luminance();
        specularSamplingWeight_ = s + d > 0 ? s / (s + d) : 0.5;
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (measure != Measure::SolidAngle || wi.z <= 0 || wo.z <= 0) return Spectrum(0.0);
        Spectrum result(0.0);
        if (hasLobe(ctx, BSDFFlags::GlossyReflection)) {
            const Vec3 h = normalize(wi + wo);
            const double F = fresnelDielectric(dot(wi, h), eta_);
            result += specularReflectance_->eval(its) * (F * distr_.eval(h) * distr_.G(wi, wo, h) / (4.0 * wi.z));
        }
        if (hasLobe(ctx, BSDFFlags::DiffuseReflection)) {
            const double T = transmittance_->eval(wi.z) * transmittance_->eval(wo.z);
            result += diffuseAlbedo(its) * (kInvPi * wo.z * T * invEta2_);
        }
        return result;
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (measure != Measure::SolidAngle || wi.z <= 0 || wo.z <= 0) return 0.0;
        const double pSpec = specularProbability(ctx, wi);
        double result = 0.0;
        if (pSpec > 0) {
            const Vec3 h = normalize(wi + wo);
            result += pSpec * distr_.pdf(wi, h) / (4.0 * std::abs(dot(wo, h)));
        }
        if (pSpec < 1) result += (1.0 - pSpec) * warp::squareToCosineHemispherePdf(wo);
        return result;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &u2) const override {
        if (!hasLobe(ctx, BSDFFlags::GlossyReflection | BSDFFlags::DiffuseReflection) || wi.z <= 0)
            return Spectrum(0.0);
        bs.eta = 1.0;
        if (u1 < specularProbability(ctx, wi)) {
            double mPdf;
            const Vec3 m = distr_.sample(wi, u2, mPdf);
            if (mPdf == 0) return Spectrum(0.0);
            bs.wo = reflect(wi, m);
            bs.sampledType = BSDFFlags::GlossyReflection;
        } else {
            bs.wo = warp::squareToCosineHemisphere(u2);
            bs.sampledType = BSDFFlags::DiffuseReflection;
        }
        // The weight is that of the whole mixture, so that MIS sees one consistent density.
        bs.pdf = pdf(ctx, its, wi, bs.wo, Measure::SolidAngle);
        if (bs.pdf == 0) return Spectrum(0.0);
        return eval(ctx, its, wi, bs.wo, Measure::SolidAngle) / bs.pdf;
    }

    double roughness(const Intersection &its, uint32_t lobe) const override {
        return (lobe & BSDFFlags::Glossy) ? distr_.alphaU() : BSDF::roughness(its, lobe);
    }

    Spectrum diffuseReflectance(const Intersection &its) const override { return diffuseReflectance_->eval(its); }

private:
    double specularProbability(const BSDFContext &ctx, const Vec3 &wi) const {
        const bool hasSpec = hasLobe(ctx, BSDFFlags::GlossyReflection);
        const bool hasDiff = hasLobe(ctx, BSDFFlags::DiffuseReflection);
        if (!hasSpec || !hasDiff) return hasSpec ? 1.0 : 0.0;
        // The share of energy the coating reflects, reweighted by the specular sampling weight.
        const double R = 1.0 - transmittance_->eval(wi.z);
        const double s = R * specularSamplingWeight_, d = (1.0 - R) * (1.0 - specularSamplingWeight_);
        return s + d > 0 ? s / (s + d) : 0.0;
    }
    Spectrum diffuseAlbedo(const Intersection &its) const {
        const Spectrum rho = diffuseReflectance_->eval(its);
        if (!nonlinear_) return rho / (1.0 - fdrInt_);
        return rho / (Spectrum(1.0) - rho * fdrInt_);
    }

    MicrofacetDistribution distr_;
    double eta_, invEta2_, fdrInt_ = 0;
    bool nonlinear_;
    double specularSamplingWeight_;
    std::shared_ptr<const CoatingTransmittance> transmittance_;
    std::shared_ptr<Texture> specularReflectance_, diffuseReflectance_;
};

}  // namespace

std::shared_ptr<Object> createRoughPlasticBSDF(const Properties &props, const LoadContext &) {
    const MicrofacetParams microfacet = readMicrofacetParams(props, false);
    if (microfacet.spatiallyVarying())
        props.fail("alpha",
                   "roughplastic needs a constant roughness (its coating transmittance is tabulated "
                   "per alpha); textured 'alpha' is not supported");
    const double intIOR = readDielectricIOR(props, "intIOR", "polypropylene");
    const double extIOR = readDielectricIOR(props, "extIOR", "air");
    const bool nonlinear = props.getBool("nonlinear", false);
    return std::make_shared<RoughPlastic>(microfacet.at(Intersection{}), intIOR / extIOR, nonlinear,
                                          readUnitTexture(props, "specularReflectance", Spectrum(1.0)),
                                          readUnitTexture(props, "diffuseReflectance", Spectrum(0.5)));
}

}  // namespace pf
