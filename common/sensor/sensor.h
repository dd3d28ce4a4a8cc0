// Sensors (cameras). Like emitters, a sensor samples and evaluates position (on the aperture) and
// direction separately, and can be sampled directly from a scene point, which light tracing (t = 1
// BDPT strategies) uses to splat onto the film. Raster coordinates are continuous: pixel (i, j) covers
// [i, i+1) x [j, j+1), with the crop window already applied (raster (0,0) is the crop's corner).
#pragma once
#include <memory>

#include "core/sample_sequence.h"
#include "core/spectrum.h"
#include "core/transform.h"
#include "scene/object.h"
#include "scene/records.h"

namespace pf {

class Film;
class Scene;

class Sensor : public Object {
public:
    // Generates a primary ray through continuous raster position `raster` using `aperture` for lens
    // sampling. Returns the importance weight (1 for Mitsuba's perspective and thinlens cameras).
    virtual Spectrum sampleRay(Ray &ray, const Vec2 &raster, const Vec2 &aperture) const = 0;

    // Aperture position: a point (pinhole, Measure::Discrete) or a disk (thinlens, Measure::Area).
    virtual Spectrum samplePosition(PositionSample &ps, const Vec2 &u) const = 0;
    virtual Spectrum evalPosition(const PositionSample &ps) const = 0;
    virtual double pdfPosition(const PositionSample &ps) const = 0;
    // Direction through raster position `raster` (pass uniform [0,1)^2 * film size for a random one),
    // from the aperture point ps. Sets ps.uv to the raster position.
    virtual Spectrum sampleDirection(DirectionSample &ds, PositionSample &ps, const Vec2 &raster) const = 0;
    // Importance We(p, d) of the whole image; the pixel is read from the raster position.
    virtual Spectrum evalDirection(const DirectionSample &ds, const PositionSample &ps) const = 0;
    // Solid-angle density of sampleDirection with a uniformly chosen raster position.
    virtual double pdfDirection(const DirectionSample &ds, const PositionSample &ps) const = 0;
    // evalDirection, with pdfDirection in `pdf`: a BDPT connection to the lens needs both, and a camera can
    // project the direction once for the two.
    virtual Spectrum evalDirectionAndPdf(const DirectionSample &ds, const PositionSample &ps, double &pdf) const {
        pdf = pdfDirection(ds, ps);
        return evalDirection(ds, ps);
    }

    // Sample the aperture towards ds.ref; returns importance * G / pdf (no visibility test) and sets
    // ds.uv to the raster position. Returns zero if ref projects outside the film or is clipped.
    virtual Spectrum sampleDirect(DirectSample &ds, const Vec2 &u) const = 0;
    virtual double pdfDirect(const DirectSample &ds) const = 0;
    // Raster position of a ray leaving aperture point p in direction d; false if it misses the film.
    virtual bool rasterPosition(const Vec3 &p, const Vec3 &d, Vec2 &raster) const = 0;
    // True when the aperture is a point (pinhole): paths cannot hit the lens (no t = 0 strategy).
    virtual bool deltaAperture() const = 0;
    // Finite apertures (the t = 0 strategy): where a ray arriving from the scene crosses the aperture
    // within (ray.tmin, ray.tmax); fills ps (p, n, uv = raster position, pdf, Measure::Area) and t. The
    // importance there is evalPosition(ps) * evalDirection(-ray.d). False for a pinhole.
    virtual bool intersectAperture(const Ray &ray, PositionSample &ps, double &t) const {
        (void)ray, (void)ps, (void)t;
        return false;
    }

    virtual void configure(const Scene &scene) { (void)scene; }
    const Transform &toWorld() const { return toWorld_; }
    // Medium the sensor sits in (Mitsuba: a medium child of <sensor>), nullptr for vacuum.
    const class Medium *medium() const { return medium_.get(); }
    Film &film() const { return *film_; }
    const std::shared_ptr<Film> &filmPtr() const { return film_; }
    // Samples per pixel requested by the scene's <sampler> (Mitsuba's sampleCount, default 4).
    int sampleCount() const { return sampleCount_; }
    // The numbers image tasks draw for this sensor's pixel samples (the scene's <sampler> type).
    const SampleSequence &sampleSequence() const { return sampleSequence_; }
    double nearClip() const { return nearClip_; }
    double farClip() const { return farClip_; }
    // The unit viewing direction in world space (toWorld's +z).
    const Vec3 &forward() const { return forward_; }
    // Whether world point q lies beyond the near clipping plane, a plane of constant depth along forward():
    // camera rays start there (sampleRay), so connections to the sensor skip that slab too.
    bool beyondNearClip(const Vec3 &q) const { return dot(q - origin_, forward_) >= nearClip_; }

protected:
    // Sets toWorld_ and what is derived from it (every connection to the lens asks for the origin and
    // forward direction, which were a transform and a normalization per call).
    void setToWorld(const Transform &toWorld) {
        toWorld_ = toWorld;
        origin_ = toWorld.point(Vec3(0.0));
        forward_ = normalize(toWorld.vector(Vec3(0, 0, 1)));
    }

    std::shared_ptr<Film> film_;
    std::shared_ptr<class Medium> medium_;
    int sampleCount_ = 4;
    SampleSequence sampleSequence_;
    double nearClip_ = 1e-2, farClip_ = 1e4;

private:
    Transform toWorld_;  // with origin_ and forward_ derived from it, set only through setToWorld
    Vec3 origin_, forward_{0, 0, 1};
};

}  // namespace pf
