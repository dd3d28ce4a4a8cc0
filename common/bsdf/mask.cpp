// Mitsuba 0.6 "mask": blends a nested BSDF with a Null pass-through, f = opacity f_nested +
// (1 - opacity) delta(wo + wi), e.g. for leaves cut out of a polygon by an alpha texture. The choice
// between the two is sampled with probability proportional to the (colour-averaged) opacity.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"

namespace pf {

namespace {

class Mask final : public BSDF {
public:
    Mask(std::shared_ptr<Texture> opacity, std::shared_ptr<BSDF> nested)
        : opacity_(std::move(opacity)), nested_(std::move(nested)) {
        flags_ =
            nested_->flags() | BSDFFlags::Null | BSDFFlags::FrontSide | BSDFFlags::BackSide | variationFlag(*opacity_);
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        const Spectrum opacity = opacity_->eval(its);
        Spectrum result = nested_->eval(ctx, its, wi, wo, measure) * opacity;
        if (passes(ctx, wi, wo, measure)) result += Spectrum(1.0) - opacity;
        return result;
    }

    double pdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        const double pNested = nestedProbability(ctx, its);
        double result = pNested > 0 ? pNested * nested_->pdf(ctx, its, wi, wo, measure) : 0.0;
        if (passes(ctx, wi, wo, measure)) result += 1.0 - pNested;
        return result;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &u2) const override {
        const double pNested = nestedProbability(ctx, its);
        const Spectrum opacity = opacity_->eval(its);
        if (u1 < pNested) {
            // Reuse u1, rescaled to [0, 1), for the nested BSDF's own lobe choice.
            const Spectrum weight = nested_->sample(ctx, its, wi, bs, u1 / pNested, u2);
            bs.pdf *= pNested;
            return weight * opacity / pNested;
        }
        if (!hasLobe(ctx, BSDFFlags::Null)) return Spectrum(0.0);
        bs.wo = -wi;
        bs.pdf = 1.0 - pNested;
        bs.eta = 1.0;
        bs.sampledType = BSDFFlags::Null;
        return (Spectrum(1.0) - opacity) / bs.pdf;
    }

    double roughness(const Intersection &its, uint32_t lobe) const override {
        return (lobe & BSDFFlags::Null) ? 0.0 : nested_->roughness(its, lobe);
    }
    Spectrum diffuseReflectance(const Intersection &its) const override {
        return nested_->diffuseReflectance(its) * opacity_->eval(its);
    }

private:
    static bool passes(const BSDFContext &ctx, const Vec3 &wi, const Vec3 &wo, Measure measure) {
        return measure == Measure::Discrete && hasLobe(ctx, BSDFFlags::Null) && isPassThrough(wi, wo);
    }
    double nestedProbability(const BSDFContext &ctx, const Intersection &its) const {
        const bool hasNested = hasLobe(ctx, nested_->flags() & BSDFFlags::All);
        if (!hasLobe(ctx, BSDFFlags::Null)) return hasNested ? 1.0 : 0.0;
        return hasNested ? opacity_->eval(its).average() : 0.0;
    }

    std::shared_ptr<Texture> opacity_;
    std::shared_ptr<BSDF> nested_;
};

}  // namespace

std::shared_ptr<Object> createMaskBSDF(const Properties &props, const LoadContext &) {
    std::shared_ptr<Texture> opacity = readUnitTexture(props, "opacity", Spectrum(0.5));
    return std::make_shared<Mask>(std::move(opacity), nestedBSDFs(props, 1, 1).front());
}

}  // namespace pf
