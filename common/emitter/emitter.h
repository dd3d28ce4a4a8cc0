// Emitters (Mitsuba's Emitter / AbstractEmitter). Besides direct sampling for next-event estimation,
// every emitter samples and evaluates its position and direction separately, with densities, which is
// what light tracing, BDPT and the path-space layer need (thesis appendix A4: emitter supernode ->
// emitter node -> first edge).
//
// Conventions: samplePosition returns the spatial emission divided by the position pdf;
// sampleDirection returns the directional emission profile divided by the direction pdf, so that
// their product is Le * cos / (pdfA * pdfW). evalPosition/evalDirection return the unweighted parts
// (their product is Le times the cosine at the emitter for area lights).
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/spectrum.h"
#include "scene/intersection.h"
#include "scene/object.h"
#include "scene/records.h"

namespace pf {

class Properties;
class Scene;
class Shape;

namespace EmitterFlags {
enum : uint32_t {
    DeltaPosition = 1u << 0,   // point, spot
    DeltaDirection = 1u << 1,  // directional
    OnSurface = 1u << 2,       // area emitters attached to shapes
    Infinite = 1u << 3,        // emitters at infinity (constant, envmap, directional, sky, sun, sunsky)
};
}

class Emitter : public Object {
public:
    uint32_t flags() const { return flags_; }
    bool isEnvironment() const { return (flags_ & EmitterFlags::Infinite) != 0; }
    bool isDelta() const { return (flags_ & (EmitterFlags::DeltaPosition | EmitterFlags::DeltaDirection)) != 0; }
    bool isOnSurface() const { return (flags_ & EmitterFlags::OnSurface) != 0; }

    // Called once by the scene after loading (environment emitters need the scene's bounding sphere;
    // area emitters get their shape).
    virtual void configure(const Scene &scene) { (void)scene; }
    virtual void setShape(const Shape *shape) { (void)shape; }
    const Shape *shape() const { return shape_; }

    // Radiance leaving a surface point of an area emitter towards world direction d.
    virtual Spectrum eval(const Intersection &its, const Vec3 &d) const;
    // Radiance arriving along a ray that escapes the scene (environment emitters): seen from
    // direction -ray.d.
    virtual Spectrum evalEnvironment(const Ray &ray) const;

    // Next-event estimation: samples a point towards ds.ref; returns Le * (implicit G) / pdf as seen from
    // ref, i.e. the radiance arriving at ref divided by the solid-angle pdf (no visibility test).
    virtual Spectrum sampleDirect(DirectSample &ds, const Vec2 &u) const = 0;
    // Solid-angle density of sampleDirect producing ds (ds.p, ds.n, ds.d, ds.dist filled in).
    virtual double pdfDirect(const DirectSample &ds) const = 0;

    virtual Spectrum samplePosition(PositionSample &ps, const Vec2 &u) const = 0;
    virtual Spectrum evalPosition(const PositionSample &ps) const = 0;
    virtual double pdfPosition(const PositionSample &ps) const = 0;
    virtual Spectrum sampleDirection(DirectionSample &ds, const PositionSample &ps, const Vec2 &u) const = 0;
    virtual Spectrum evalDirection(const DirectionSample &ds, const PositionSample &ps) const = 0;
    virtual double pdfDirection(const DirectionSample &ds, const PositionSample &ps) const = 0;

    // Environment emitters (constant, envmap) are the inside of a sphere around the scene and the camera
    // that emits inwards (see emitter/environment.h), so that light tracing and BDPT treat their vertices
    // with ordinary area densities. For a ray leaving the scene this fills ds.p and ds.n (inward) on that
    // sphere, ds.d = ray.d, ds.dist = infinity, ds.measure and ds.object, ready for pdfDirect and for the
    // position/direction densities. Returns false for emitters that an escaping ray cannot reach.
    virtual bool fillDirectSample(DirectSample &ds, const Ray &ray) const;

    // Sampling weight for emitter selection (Mitsuba's samplingWeight, default 1).
    double samplingWeight() const { return samplingWeight_; }
    // Whether specular manifold sampling connects to this emitter (XML boolean causticEmitter, an extension of
    // Mitsuba 0.6; nullopt when not given, see manifold/sms.h for the default).
    std::optional<bool> causticEmitter() const { return causticEmitter_; }
    // Total emitted power (used for display and statistics).
    virtual Spectrum power() const = 0;

    // Emitters that come into the scene with this one. Mitsuba's compound emitters make several: `sunsky`
    // with sunRadiusScale = 0 is a sky beside a directional sun. The scene adds them after this one.
    virtual std::vector<std::shared_ptr<Emitter>> companions() const { return {}; }

protected:
    // Reads the parameters every emitter accepts (Mitsuba's samplingWeight).
    void configureCommon(const Properties &props);

    uint32_t flags_ = 0;
    double samplingWeight_ = 1.0;
    std::optional<bool> causticEmitter_;
    const Shape *shape_ = nullptr;
};

}  // namespace pf
