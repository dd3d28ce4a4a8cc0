// Mitsuba 0.6 "twosided": makes one-sided reflection models usable from both sides. A direction pair
// below the surface is mirrored to the front (z -> -z for wi and wo) and handed to the nested BSDF, or
// to the second nested BSDF if there is one (a different material on the back). Models with
// transmission cannot be nested: mirroring would turn their transmission into reflection.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"

namespace pf {

namespace {

Vec3 flipZ(const Vec3 &v) { return {v.x, v.y, -v.z}; }

class TwoSided final : public BSDF {
public:
    TwoSided(std::shared_ptr<BSDF> front, std::shared_ptr<BSDF> back)
        : front_(std::move(front)), back_(std::move(back)) {
        const uint32_t sides = BSDFFlags::FrontSide | BSDFFlags::BackSide;
        flags_ = ((front_->flags() | back_->flags()) & ~sides) | sides;
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        if (wi.z < 0) return back_->eval(ctx, its, flipZ(wi), flipZ(wo), measure);
        return front_->eval(ctx, its, wi, wo, measure);
    }

    double pdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        if (wi.z < 0) return back_->pdf(ctx, its, flipZ(wi), flipZ(wo), measure);
        return front_->pdf(ctx, its, wi, wo, measure);
    }

    Spectrum evalPdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                     double &pdfOut) const override {
        if (wi.z < 0) return back_->evalPdf(ctx, its, flipZ(wi), flipZ(wo), pdfOut);
        return front_->evalPdf(ctx, its, wi, wo, pdfOut);
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &u2) const override {
        if (wi.z >= 0) return front_->sample(ctx, its, wi, bs, u1, u2);
        const Spectrum weight = back_->sample(ctx, its, flipZ(wi), bs, u1, u2);
        bs.wo = flipZ(bs.wo);
        return weight;
    }

    // The side is that of the ray that reached the intersection.
    double roughness(const Intersection &its, uint32_t lobe) const override { return side(its).roughness(its, lobe); }
    Spectrum diffuseReflectance(const Intersection &its) const override { return side(its).diffuseReflectance(its); }

private:
    const BSDF &side(const Intersection &its) const { return its.wi.z < 0 ? *back_ : *front_; }

    std::shared_ptr<BSDF> front_, back_;
};

}  // namespace

std::shared_ptr<Object> createTwoSidedBSDF(const Properties &props, const LoadContext &) {
    const std::vector<std::shared_ptr<BSDF>> nested = nestedBSDFs(props, 1, 2);
    for (const std::shared_ptr<BSDF> &b : nested)
        if (b->flags() & BSDFFlags::Transmission)
            props.fail("twosided: a nested BSDF has a transmission component; only reflection models can be nested");
    return std::make_shared<TwoSided>(nested.front(), nested.back());
}

}  // namespace pf
