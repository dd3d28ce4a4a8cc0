// Mitsuba 0.6's "area" emitter: uniform radiance leaving the side of a shape that its geometric normal
// points to (one-sided, as in Mitsuba). The emission factors into a spatial part pi * L (the radiant
// exitance) and a directional part cos / pi (a normalized cosine lobe), which is the split light tracing
// and BDPT use (Veach 1997, §8.3.2: Le = Le0 * Le1).
#include "core/frame.h"
#include "core/warp.h"
#include "emitter/emitter.h"
#include "emitter/endpoint.h"
#include "scene/plugins.h"
#include "scene/shape.h"

namespace pf {

namespace {

class AreaEmitter final : public Emitter {
public:
    explicit AreaEmitter(const Properties &props) : radiance_(nonNegativeSpectrum(props, "radiance", Spectrum(1.0))) {
        configureCommon(props);
        flags_ = EmitterFlags::OnSurface;
    }

    void setShape(const Shape *shape) override { shape_ = shape; }
    void configure(const Scene &) override {
        if (!shape_) throw SceneError(location(), "an area emitter must be declared inside a shape");
    }

    Spectrum eval(const Intersection &its, const Vec3 &d) const override {
        return dot(its.n, d) > 0 ? radiance_ : Spectrum(0.0);
    }

    // The returned density is that of the shape's sampling even when the sampled point faces away from
    // ref (zero radiance then), so that pdfDirect is the true density of every direction produced.
    Spectrum sampleDirect(DirectSample &ds, const Vec2 &u) const override {
        shape_->sampleDirect(ds, u);
        ds.object = this;
        ds.measure = Measure::SolidAngle;
        if (!(ds.pdf > 0) || dot(ds.n, ds.d) >= 0) return Spectrum(0.0);
        return radiance_ / ds.pdf;
    }
    double pdfDirect(const DirectSample &ds) const override {
        return ds.measure == Measure::SolidAngle ? shape_->pdfDirect(ds) : 0.0;
    }

    Spectrum samplePosition(PositionSample &ps, const Vec2 &u) const override {
        shape_->samplePosition(ps, u);
        return ps.pdf > 0 ? evalPosition(ps) / ps.pdf : Spectrum(0.0);
    }
    Spectrum evalPosition(const PositionSample &ps) const override {
        return ps.measure == Measure::Area ? radiance_ * kPi : Spectrum(0.0);
    }
    double pdfPosition(const PositionSample &ps) const override {
        return ps.measure == Measure::Area ? shape_->pdfPosition(ps) : 0.0;
    }

    // Cosine-weighted directions about the normal: the directional profile cos / pi is sampled exactly.
    Spectrum sampleDirection(DirectionSample &ds, const PositionSample &ps, const Vec2 &u) const override {
        const Vec3 local = warp::squareToCosineHemisphere(u);
        ds.d = Frame(ps.n).toWorld(local);
        ds.pdf = warp::squareToCosineHemispherePdf(local);
        ds.measure = Measure::SolidAngle;
        return Spectrum(ds.pdf > 0 ? 1.0 : 0.0);
    }
    // The directional profile cos / pi is itself the density sampled above.
    Spectrum evalDirection(const DirectionSample &ds, const PositionSample &ps) const override {
        return Spectrum(pdfDirection(ds, ps));
    }
    double pdfDirection(const DirectionSample &ds, const PositionSample &ps) const override {
        if (ds.measure != Measure::SolidAngle) return 0.0;
        return std::max(0.0, dot(ps.n, ds.d)) * kInvPi;
    }

    Spectrum power() const override { return radiance_ * (kPi * shape_->surfaceArea()); }

private:
    Spectrum radiance_;
};

}  // namespace

std::shared_ptr<Object> createAreaEmitter(const Properties &props, const LoadContext &) {
    return std::make_shared<AreaEmitter>(props);
}

}  // namespace pf
