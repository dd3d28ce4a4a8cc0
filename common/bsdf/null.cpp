// Mitsuba 0.6 "null": an index-matched boundary. Its only lobe is a Null pass-through (wo = -wi with
// weight one), which integrators follow without counting a scattering event; it marks the boundaries
// of participating media and hides geometry.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"

namespace pf {

namespace {

class NullBSDF final : public BSDF {
public:
    NullBSDF() { flags_ = BSDFFlags::Null | BSDFFlags::FrontSide | BSDFFlags::BackSide; }

    Spectrum eval(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        return Spectrum(active(ctx, wi, wo, measure) ? 1.0 : 0.0);
    }

    double pdf(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        return active(ctx, wi, wo, measure) ? 1.0 : 0.0;
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &, const Vec3 &wi, BSDFSample &bs, double,
                    const Vec2 &) const override {
        if (!hasLobe(ctx, BSDFFlags::Null)) return Spectrum(0.0);
        bs.wo = -wi;
        bs.pdf = 1.0;
        bs.eta = 1.0;
        bs.sampledType = BSDFFlags::Null;
        return Spectrum(1.0);
    }

private:
    static bool active(const BSDFContext &ctx, const Vec3 &wi, const Vec3 &wo, Measure measure) {
        return measure == Measure::Discrete && hasLobe(ctx, BSDFFlags::Null) && isPassThrough(wi, wo);
    }
};

}  // namespace

std::shared_ptr<Object> createNullBSDF(const Properties &, const LoadContext &) { return std::make_shared<NullBSDF>(); }

}  // namespace pf
