// Mitsuba 0.6's "spot" emitter: a point source at the origin of toWorld shining along local +z. The
// intensity is full inside beamWidth and falls off linearly in angle to zero at cutoffAngle (Mitsuba's
// falloff curve). Directions are sampled uniformly in the cutoff cone, as Mitsuba does.
#include "core/warp.h"
#include "emitter/emitter.h"
#include "emitter/endpoint.h"
#include "scene/plugins.h"

namespace pf {

namespace {

class SpotEmitter final : public Emitter {
public:
    explicit SpotEmitter(const Properties &props)
        : intensity_(nonNegativeSpectrum(props, "intensity", Spectrum(1.0))),
          toWorld_(rigidTransform(props, "toWorld")) {
        configureCommon(props);
        flags_ = EmitterFlags::DeltaPosition;
        const double cutoffDeg = props.getFloat("cutoffAngle", 20.0);
        if (!(cutoffDeg > 0 && cutoffDeg <= 180)) props.fail("cutoffAngle", "must lie in (0, 180] degrees");
        const double beamDeg = props.getFloat("beamWidth", cutoffDeg * 0.75);
        if (!(beamDeg >= 0 && beamDeg <= cutoffDeg)) props.fail("beamWidth", "must lie in [0, cutoffAngle] degrees");
        cutoff_ = degToRad(cutoffDeg);
        beamWidth_ = degToRad(beamDeg);
        cosCutoff_ = std::cos(cutoff_);
        cosBeamWidth_ = std::cos(beamWidth_);
        position_ = toWorld_.point(Vec3(0.0));
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
        return intensity_ * (falloff(-ds.d) / (ds.dist * ds.dist));
    }
    double pdfDirect(const DirectSample &ds) const override { return ds.measure == Measure::Discrete ? 1.0 : 0.0; }

    // As for Mitsuba's spot light, the spatial part is 4 pi I and the directional part falloff / (4 pi).
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
        const Vec3 local = warp::squareToUniformCone(u, cosCutoff_);
        ds.d = normalize(toWorld_.vector(local));
        ds.pdf = warp::squareToUniformConePdf(local, cosCutoff_);
        ds.measure = Measure::SolidAngle;
        return ds.pdf > 0 ? Spectrum(falloffLocal(local) * kInvFourPi / ds.pdf) : Spectrum(0.0);
    }
    Spectrum evalDirection(const DirectionSample &ds, const PositionSample &) const override {
        return ds.measure == Measure::SolidAngle ? Spectrum(falloff(ds.d) * kInvFourPi) : Spectrum(0.0);
    }
    double pdfDirection(const DirectionSample &ds, const PositionSample &) const override {
        if (ds.measure != Measure::SolidAngle) return 0.0;
        return warp::squareToUniformConePdf(toLocal(ds.d), cosCutoff_);
    }

    // I times the integral of the falloff over the sphere: 2 pi (1 - cos b) inside the beam plus the
    // linear ramp, whose integral 2 pi int_b^c (c - t) / (c - b) sin t dt = 2 pi (cos b - (sin c - sin b) / (c - b))
    // follows by parts; the sum is 2 pi (1 - (sin c - sin b) / (c - b)).
    Spectrum power() const override {
        const double c = cutoff_, b = beamWidth_;
        const double solidAngle =
            c > b ? 2.0 * kPi * (1.0 - (std::sin(c) - std::sin(b)) / (c - b)) : 2.0 * kPi * (1.0 - cosCutoff_);
        return intensity_ * solidAngle;
    }

private:
    Vec3 toLocal(const Vec3 &d) const { return normalize(toWorld_.inverse().vector(d)); }
    double falloff(const Vec3 &worldDir) const { return falloffLocal(toLocal(worldDir)); }
    double falloffLocal(const Vec3 &d) const {
        const double cosTheta = d.z;
        if (cosTheta <= cosCutoff_) return 0.0;
        if (cosTheta >= cosBeamWidth_) return 1.0;
        return (cutoff_ - safeAcos(cosTheta)) / (cutoff_ - beamWidth_);
    }

    Spectrum intensity_;
    Transform toWorld_;
    Vec3 position_;
    double cutoff_, beamWidth_, cosCutoff_, cosBeamWidth_;
};

}  // namespace

std::shared_ptr<Object> createSpotEmitter(const Properties &props, const LoadContext &) {
    return std::make_shared<SpotEmitter>(props);
}

}  // namespace pf
