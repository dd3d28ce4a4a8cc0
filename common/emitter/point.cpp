// Mitsuba 0.6's "point" emitter: an isotropic point source of radiant intensity I (W/sr). Its position
// is a delta (Measure::Discrete); the emission splits into 4 pi I (the power) times the uniform
// directional profile 1 / (4 pi).
#include "core/warp.h"
#include "emitter/emitter.h"
#include "emitter/endpoint.h"
#include "scene/plugins.h"

namespace pf {

namespace {

class PointEmitter final : public Emitter {
public:
    explicit PointEmitter(const Properties &props)
        : intensity_(nonNegativeSpectrum(props, "intensity", Spectrum(1.0))) {
        configureCommon(props);
        flags_ = EmitterFlags::DeltaPosition;
        // Mitsuba accepts either a position or a toWorld transform whose origin is the light.
        if (props.has("position")) {
            if (props.has("toWorld")) props.fail("position", "cannot be combined with 'toWorld'");
            position_ = props.getPoint("position");
        } else {
            position_ = props.getTransform("toWorld", Transform()).point(Vec3(0.0));
        }
    }

    Spectrum sampleDirect(DirectSample &ds, const Vec2 &) const override {
        const Vec3 toLight = position_ - ds.ref;
        ds.dist = toLight.length();
        ds.p = position_;
        ds.n = Vec3(0.0);
        ds.uv = Vec2(0.5, 0.5);
        ds.pdf = 1.0;
        ds.measure = Measure::Discrete;
        ds.object = this;
        if (!(ds.dist > 0)) return Spectrum(0.0);
        ds.d = toLight / ds.dist;
        return intensity_ / (ds.dist * ds.dist);
    }
    double pdfDirect(const DirectSample &ds) const override { return ds.measure == Measure::Discrete ? 1.0 : 0.0; }

    Spectrum samplePosition(PositionSample &ps, const Vec2 &) const override {
        ps.p = position_;
        ps.n = Vec3(0.0);
        ps.pdf = 1.0;
        ps.measure = Measure::Discrete;
        return evalPosition(ps);
    }
    Spectrum evalPosition(const PositionSample &ps) const override {
        return ps.measure == Measure::Discrete ? intensity_ * (4.0 * kPi) : Spectrum(0.0);
    }
    double pdfPosition(const PositionSample &ps) const override { return ps.measure == Measure::Discrete ? 1.0 : 0.0; }

    Spectrum sampleDirection(DirectionSample &ds, const PositionSample &, const Vec2 &u) const override {
        ds.d = warp::squareToUniformSphere(u);
        ds.pdf = warp::squareToUniformSpherePdf();
        ds.measure = Measure::SolidAngle;
        return Spectrum(1.0);
    }
    // The uniform profile 1 / (4 pi) is itself the density sampled above.
    Spectrum evalDirection(const DirectionSample &ds, const PositionSample &ps) const override {
        return Spectrum(pdfDirection(ds, ps));
    }
    double pdfDirection(const DirectionSample &ds, const PositionSample &) const override {
        return ds.measure == Measure::SolidAngle ? warp::squareToUniformSpherePdf() : 0.0;
    }

    Spectrum power() const override { return intensity_ * (4.0 * kPi); }

private:
    Spectrum intensity_;
    Vec3 position_;
};

}  // namespace

std::shared_ptr<Object> createPointEmitter(const Properties &props, const LoadContext &) {
    return std::make_shared<PointEmitter>(props);
}

}  // namespace pf
