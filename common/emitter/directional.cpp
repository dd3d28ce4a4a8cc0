// Mitsuba 0.6's "directional" emitter: parallel light of a given irradiance (W/m^2 on a surface facing it)
// travelling along `direction`, or along local +z of toWorld. For light tracing the beam enters the
// scene through the disk of the bounding sphere perpendicular to it (pbrt-v3 §12.4, Mitsuba's
// directional emitter): positions are uniform on that disk, and the direction is a delta.
#include "emitter/directional.h"

#include "core/frame.h"
#include "core/warp.h"
#include "emitter/endpoint.h"
#include "emitter/environment.h"
#include "scene/plugins.h"

namespace pf {

namespace {

class DirectionalEmitter final : public InfiniteEmitter {
public:
    explicit DirectionalEmitter(const Properties &props)
        : irradiance_(nonNegativeSpectrum(props, "irradiance", Spectrum(1.0))) {
        configureCommon(props);
        flags_ = EmitterFlags::DeltaDirection | EmitterFlags::Infinite;
        if (props.has("direction")) {
            if (props.has("toWorld")) props.fail("direction", "cannot be combined with 'toWorld'");
            const Vec3 d = props.getVector("direction");
            if (!(d.length() > 0)) props.fail("direction", "must be a non-zero vector");
            direction_ = normalize(d);
        } else {
            direction_ = normalize(rigidTransform(props, "toWorld").vector(Vec3(0, 0, 1)));
        }
    }
    DirectionalEmitter(const Vec3 &direction, const Spectrum &irradiance, double samplingWeight)
        : irradiance_(irradiance), direction_(normalize(direction)) {
        flags_ = EmitterFlags::DeltaDirection | EmitterFlags::Infinite;
        samplingWeight_ = samplingWeight;
    }

    // The light arrives at ref from -direction; its point is where that line crosses the entry disk.
    Spectrum sampleDirect(DirectSample &ds, const Vec2 &) const override {
        const double distance = dot(ds.ref - diskCenter(), direction_);
        ds.d = -direction_;
        ds.n = direction_;
        ds.p = ds.ref - direction_ * distance;
        ds.dist = kInfinity;
        ds.pdf = 1.0;
        ds.measure = Measure::Discrete;
        ds.object = this;
        return distance >= 0 ? irradiance_ : Spectrum(0.0);
    }
    double pdfDirect(const DirectSample &ds) const override { return ds.measure == Measure::Discrete ? 1.0 : 0.0; }

    Spectrum samplePosition(PositionSample &ps, const Vec2 &u) const override {
        const Vec2 disk = warp::squareToUniformDiskConcentric(u);
        const Frame frame(direction_);
        ps.p = diskCenter() + (frame.s * disk.x + frame.t * disk.y) * radius_;
        ps.n = direction_;
        ps.measure = Measure::Area;
        ps.pdf = pdfPosition(ps);
        return evalPosition(ps) / ps.pdf;
    }
    Spectrum evalPosition(const PositionSample &ps) const override {
        return ps.measure == Measure::Area ? irradiance_ : Spectrum(0.0);
    }
    double pdfPosition(const PositionSample &ps) const override {
        return ps.measure == Measure::Area ? 1.0 / (kPi * radius_ * radius_) : 0.0;
    }

    Spectrum sampleDirection(DirectionSample &ds, const PositionSample &, const Vec2 &) const override {
        ds.d = direction_;
        ds.pdf = 1.0;
        ds.measure = Measure::Discrete;
        return Spectrum(1.0);
    }
    Spectrum evalDirection(const DirectionSample &ds, const PositionSample &) const override {
        return Spectrum(ds.measure == Measure::Discrete ? 1.0 : 0.0);
    }
    double pdfDirection(const DirectionSample &ds, const PositionSample &) const override {
        return ds.measure == Measure::Discrete ? 1.0 : 0.0;
    }

    Spectrum power() const override { return irradiance_ * (kPi * radius_ * radius_); }

private:
    Vec3 diskCenter() const { return center_ - direction_ * radius_; }

    Spectrum irradiance_;
    Vec3 direction_;
};

}  // namespace

std::shared_ptr<Object> createDirectionalEmitter(const Properties &props, const LoadContext &) {
    return std::make_shared<DirectionalEmitter>(props);
}

std::shared_ptr<Emitter> makeDirectionalEmitter(const Vec3 &direction, const Spectrum &irradiance,
                                                double samplingWeight) {
    return std::make_shared<DirectionalEmitter>(direction, irradiance, samplingWeight);
}

}  // namespace pf
