// Emitters at infinity (directional, constant, envmap) and the sphere that stands in for infinity.
//
// Light tracing and BDPT start paths on emitters with a position density followed by a direction density
// conditioned on it. An environment has no positions, so, like Mitsuba 0.6, pathfarm places one: a sphere
// around the scene and the camera (the bounding sphere of both, enlarged by 10% so that no surface
// touches it). For radiance that depends on direction only, the inside of such a sphere emitting L(-w)
// in every inward direction w creates exactly the radiance field of the environment inside it, so
// treating environment vertices as points on that sphere (area measure, inward normal) is exact and lets
// the integrators use one set of density conversions for every emitter. Positions are uniform on the
// sphere; directions follow the environment's own importance sampling (uniform for constant, the map for
// envmap), whichever way they face: those leaving the sphere carry no radiance. Direct sampling draws a
// direction from the same importance sampling and reports where it meets the sphere.
#pragma once
#include "core/transform.h"
#include "emitter/emitter.h"

namespace pf {

// An emitter whose light tracing needs the extent of the scene (directional, constant, envmap).
class InfiniteEmitter : public Emitter {
public:
    // Fits the sphere around the scene's bounds and the sensor's position.
    void configure(const Scene &scene) override;
    // Sets the sphere directly (used by configure, and by tests without a scene).
    void setBoundingSphere(const Vec3 &center, double radius);
    const Vec3 &sphereCenter() const { return center_; }
    double sphereRadius() const { return radius_; }

protected:
    Vec3 center_;
    double radius_ = 1.0;
};

// An environment of radiance L(v) arriving from direction v (a ray looking along v sees L(v)), defined in
// local coordinates that toWorld (a rotation) takes to the world.
class EnvironmentEmitter : public InfiniteEmitter {
public:
    Spectrum evalEnvironment(const Ray &ray) const override;
    Spectrum sampleDirect(DirectSample &ds, const Vec2 &u) const override;
    double pdfDirect(const DirectSample &ds) const override;
    Spectrum samplePosition(PositionSample &ps, const Vec2 &u) const override;
    Spectrum evalPosition(const PositionSample &ps) const override;
    double pdfPosition(const PositionSample &ps) const override;
    Spectrum sampleDirection(DirectionSample &ds, const PositionSample &ps, const Vec2 &u) const override;
    Spectrum evalDirection(const DirectionSample &ds, const PositionSample &ps) const override;
    double pdfDirection(const DirectionSample &ds, const PositionSample &ps) const override;
    bool fillDirectSample(DirectSample &ds, const Ray &ray) const override;
    // Power entering the sphere: every direction crosses its projected disk pi R^2.
    Spectrum power() const override;

protected:
    explicit EnvironmentEmitter(const Transform &toWorld);

    // The environment in local coordinates: radiance seen looking along unit vector v, a direction sampler
    // with its solid-angle density, and the integral of L over the sphere of directions.
    virtual Spectrum radianceLocal(const Vec3 &v) const = 0;
    virtual Vec3 sampleLocal(const Vec2 &u, double &pdf) const = 0;
    virtual double pdfLocal(const Vec3 &v) const = 0;
    virtual Spectrum integratedRadiance() const = 0;

private:
    Vec3 toLocal(const Vec3 &v) const { return normalize(worldToLocal_.vector(v)); }
    // Far intersection of the ray (o, d) with the sphere, seen from inside: point and inward normal.
    bool hitSphere(const Vec3 &o, const Vec3 &d, Vec3 &p, Vec3 &n) const;

    Transform toWorld_, worldToLocal_;
};

}  // namespace pf
