#include "emitter/environment.h"

#include "core/warp.h"
#include "scene/scene.h"

namespace pf {

void InfiniteEmitter::configure(const Scene &scene) {
    AABB box = scene.bounds();
    if (const auto &sensor = scene.sensorPtr()) box.expand(sensor->toWorld().point(Vec3(0.0)));
    if (!box.valid()) {
        setBoundingSphere(Vec3(0.0), 1.0);
        return;
    }
    // 10% margin: light-traced paths must not start on a surface that touches the sphere.
    const double radius = 1.1 * 0.5 * box.extents().length();
    setBoundingSphere(box.center(), radius > 0 ? radius : 1.0);
}

void InfiniteEmitter::setBoundingSphere(const Vec3 &center, double radius) {
    center_ = center;
    radius_ = radius;
}

EnvironmentEmitter::EnvironmentEmitter(const Transform &toWorld) : toWorld_(toWorld), worldToLocal_(toWorld.inverse()) {
    flags_ = EmitterFlags::Infinite;
}

bool EnvironmentEmitter::hitSphere(const Vec3 &o, const Vec3 &d, Vec3 &p, Vec3 &n) const {
    const Vec3 oc = o - center_;
    const double b = dot(oc, d), c = oc.lengthSquared() - radius_ * radius_;
    const double disc = b * b - c;
    if (!(disc >= 0)) return false;
    // The far root, written so as not to cancel when o lies near the centre.
    const double t = b <= 0 ? -b + std::sqrt(disc) : c < 0 ? -c / (b + std::sqrt(disc)) : -1.0;
    if (!(t > 0)) return false;
    p = o + d * t;
    n = normalize(center_ - p);
    return true;
}

Spectrum EnvironmentEmitter::evalEnvironment(const Ray &ray) const { return radianceLocal(toLocal(ray.d)); }

Spectrum EnvironmentEmitter::sampleDirect(DirectSample &ds, const Vec2 &u) const {
    double pdf = 0;
    const Vec3 local = sampleLocal(u, pdf);
    ds.d = normalize(toWorld_.vector(local));
    ds.dist = kInfinity;
    ds.measure = Measure::SolidAngle;
    ds.object = this;
    ds.pdf = pdf;
    if (!(pdf > 0) || !hitSphere(ds.ref, ds.d, ds.p, ds.n)) {
        ds.pdf = 0;
        return Spectrum(0.0);
    }
    return radianceLocal(local) / pdf;
}

double EnvironmentEmitter::pdfDirect(const DirectSample &ds) const {
    return ds.measure == Measure::SolidAngle ? pdfLocal(toLocal(ds.d)) : 0.0;
}

bool EnvironmentEmitter::fillDirectSample(DirectSample &ds, const Ray &ray) const {
    ds.d = normalize(ray.d);
    if (!hitSphere(ray.o, ds.d, ds.p, ds.n)) return false;
    ds.ref = ray.o;
    ds.dist = kInfinity;
    ds.measure = Measure::SolidAngle;
    ds.object = this;
    return true;
}

Spectrum EnvironmentEmitter::samplePosition(PositionSample &ps, const Vec2 &u) const {
    const Vec3 d = warp::squareToUniformSphere(u);
    ps.p = center_ + d * radius_;
    ps.n = -d;
    ps.measure = Measure::Area;
    ps.pdf = pdfPosition(ps);
    return evalPosition(ps) / ps.pdf;
}

// All of the emission is directional: the spatial factor is 1 and evalDirection carries L * cos.
Spectrum EnvironmentEmitter::evalPosition(const PositionSample &ps) const {
    return Spectrum(ps.measure == Measure::Area ? 1.0 : 0.0);
}

double EnvironmentEmitter::pdfPosition(const PositionSample &ps) const {
    return ps.measure == Measure::Area ? 1.0 / (4.0 * kPi * radius_ * radius_) : 0.0;
}

// The emitted direction w is opposite to the direction -w in which a ray would look to see that light.
Spectrum EnvironmentEmitter::sampleDirection(DirectionSample &ds, const PositionSample &ps, const Vec2 &u) const {
    double pdf = 0;
    const Vec3 local = sampleLocal(u, pdf);
    ds.d = -normalize(toWorld_.vector(local));
    ds.pdf = pdf;
    ds.measure = Measure::SolidAngle;
    return pdf > 0 ? evalDirection(ds, ps) / pdf : Spectrum(0.0);
}

Spectrum EnvironmentEmitter::evalDirection(const DirectionSample &ds, const PositionSample &ps) const {
    const double cosTheta = dot(ps.n, ds.d);
    if (ds.measure != Measure::SolidAngle || cosTheta <= 0) return Spectrum(0.0);
    return radianceLocal(toLocal(-ds.d)) * cosTheta;
}

double EnvironmentEmitter::pdfDirection(const DirectionSample &ds, const PositionSample &) const {
    return ds.measure == Measure::SolidAngle ? pdfLocal(toLocal(-ds.d)) : 0.0;
}

Spectrum EnvironmentEmitter::power() const { return integratedRadiance() * (kPi * radius_ * radius_); }

}  // namespace pf
