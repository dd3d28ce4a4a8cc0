// The scene: shapes in an Embree BVH, emitters, the sensor, and the integrator/sampler settings read
// from the file. Ray queries count themselves (rays/s figures).
#pragma once
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/distribution.h"
#include "emitter/emitter.h"
#include "image/film.h"
#include "scene/intersection.h"
#include "scene/portal.h"
#include "scene/properties.h"
#include "scene/shape.h"
#include "sensor/sensor.h"

namespace pf {

class Scene : public Object {
public:
    Scene();
    ~Scene() override;
    Scene(const Scene &) = delete;
    Scene &operator=(const Scene &) = delete;

    void addShape(std::shared_ptr<Shape> shape);
    void addEmitter(std::shared_ptr<Emitter> emitter);  // non-shape emitters (point, envmap, ...)
    // Portals of the portal perturbation (scene/portal.h): kept apart from the geometry, so that no ray sees them.
    void addPortal(std::shared_ptr<const Portal> portal) { portals_.push_back(std::move(portal)); }
    void setSensor(std::shared_ptr<Sensor> sensor) { sensor_ = std::move(sensor); }
    // Changes the film resolution (crop reset to the full film) and lets the sensor recompute its
    // raster mapping. Used by benchmarks and previews.
    void resizeFilm(int width, int height) {
        sensor_->film().resize(width, height);
        sensor_->configure(*this);
    }
    void setIntegratorProperties(Properties p) { integratorProps_ = std::move(p); }
    // Warnings of the load (unused parameters), in file order, for the caller to show.
    void setWarnings(std::vector<SceneWarning> w) { warnings_ = std::move(w); }
    const std::vector<SceneWarning> &warnings() const { return warnings_; }
    // Builds the BVH, configures emitters/sensor and the emitter-selection distribution.
    // Throws SceneError if there is no sensor.
    void finalize();

    // Closest hit; fills its (with its.wi set from -ray.d). Returns false on a miss.
    bool intersect(const Ray &ray, Intersection &its) const;
    // Any hit in (ray.tmin, ray.tmax).
    bool occluded(const Ray &ray) const;
    // Ray leaving its in world direction d, offset along the geometric normal to avoid self-hits.
    Ray spawnRay(const Intersection &its, const Vec3 &d) const;
    // Shadow ray from its to point p (tmax stops just short of p).
    Ray spawnRayTo(const Intersection &its, const Vec3 &p) const;
    Ray spawnRayTo(const Vec3 &from, const Vec3 &p) const;
    // Robust offset length at point p (relative to the coordinates' magnitude).
    double epsilonAt(const Vec3 &p) const;

    // Emitter selection (proportional to samplingWeight) and direct sampling from ds.ref:
    // returns radiance / (selection pmf * pdf), ds.pdf includes the selection pmf. No visibility test.
    Spectrum sampleEmitterDirect(DirectSample &ds, const Vec2 &u) const;
    // Density (including the selection pmf) of sampleEmitterDirect producing ds for `emitter`.
    double pdfEmitterDirect(const DirectSample &ds, const Emitter *emitter) const;
    // Emitter selection for light tracing; returns the emitter and its selection pmf.
    const Emitter *sampleEmitter(double u, double &pmf) const;
    double emitterPmf(const Emitter *e) const;

    const std::vector<std::shared_ptr<Shape>> &shapes() const { return shapes_; }
    const std::vector<std::shared_ptr<Emitter>> &emitters() const { return emitters_; }
    const Emitter *environment() const { return environment_; }
    const std::vector<std::shared_ptr<const Portal>> &portals() const { return portals_; }
    const Sensor &sensor() const { return *sensor_; }
    const std::shared_ptr<Sensor> &sensorPtr() const { return sensor_; }
    const Properties &integratorProperties() const { return integratorProps_; }
    const AABB &bounds() const { return bounds_; }
    // Bounding sphere of the scene (environment emitters sample positions on its disk).
    Vec3 boundingSphereCenter() const { return bounds_.center(); }
    double boundingSphereRadius() const { return bounds_.extents().length() * 0.5; }

    // True if some surface lets light pass unchanged (a BSDF with a Null lobe: null, mask, thin dielectric,
    // index-matched medium boundaries). Without such surfaces a shadow ray is a plain occlusion query.
    bool hasPassThroughSurfaces() const { return passThrough_; }

    // Rays traced (intersect + occluded) by the calling thread so far. Thread-local, so counting costs
    // nothing on the hot path; render loops read it before and after their work.
    static uint64_t threadRayCount();
    // The Embree scene, for benchmarks that measure raw traversal throughput.
    RTCScene embreeScene() const { return rtc_; }
    // A ray as a renderer traced it: an intersect query, or an occlusion query (shadow).
    struct TracedRay {
        Ray ray;
        bool shadow = false;
    };
    // While `log` is set on the calling thread (nullptr stops), every ray that thread traces is appended to
    // it: bench_pathtracer replays a renderer's own rays through raw Embree, to compare the renderer with
    // traversal on the same rays rather than on random ones. Thread-local, one pointer test per ray.
    static void recordThreadRays(std::vector<TracedRay> *log);
    // The Embree query of a traced ray and nothing else (no hit record, no counting, no recording);
    // returns whether it hit.
    bool traverse(const TracedRay &r) const;
    size_t primitiveCount() const;

private:
    RTCDevice device_ = nullptr;
    RTCScene rtc_ = nullptr;
    std::vector<std::shared_ptr<Shape>> shapes_;
    std::vector<const Shape *> geomToShape_;
    std::vector<std::shared_ptr<Emitter>> emitters_;  // all emitters, incl. area emitters of shapes
    std::vector<std::shared_ptr<const Portal>> portals_;
    const Emitter *environment_ = nullptr;
    std::shared_ptr<Sensor> sensor_;
    Properties integratorProps_;
    std::vector<SceneWarning> warnings_;
    Distribution1D emitterDist_;
    AABB bounds_;
    bool passThrough_ = false;
};

// Loads a Mitsuba 0.5/0.6 XML scene. `defines` supplies values for $name parameters (CLI -D), overriding
// <default> elements. Throws SceneError with file and line on any problem; a parameter that its plugin
// does not use is one too when `strict`, else a warning in Scene::warnings() (as Mitsuba 0.6).
std::unique_ptr<Scene> loadScene(const std::string &path,
                                 const std::vector<std::pair<std::string, std::string>> &defines = {},
                                 bool strict = false);

// Secondary rays start off the surface by epsilonAt(p) = 2^-24 (256 max_i |p_i| + 1500) along the
// geometric normal. The offset has to exceed the error of Embree's single-precision traversal and triangle
// test (hit points themselves are recomputed in double): a few float ulps of the coordinates involved
// (pbrt-v3 §3.9's error bounds), for which 256 ulps of |p| leave a wide margin far from the origin. Near
// the origin |p| says nothing about the size of the triangles around p, whose magnitude sets the error,
// so a constant term takes over there: Mitsuba 3's math::RayEpsilon (1500 ulps of 1, in scene units),
// enough for triangles a few hundred units across. Analytic shapes intersect in double and need far less.
// The price: geometry thinner than the offset (about 1e-4 near the origin, 1.5e-5 |p| far from it) can be
// leaked through.
inline constexpr double kRayEpsilonRelative = 256.0 * 0x1p-24;
inline constexpr double kRayEpsilonAbsolute = 1500.0 * 0x1p-24;

inline double Scene::epsilonAt(const Vec3 &p) const {
    return kRayEpsilonRelative * std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) + kRayEpsilonAbsolute;
}

// The origin moves along the geometric normal to the side the ray leaves to, so that transmitted rays
// start below the surface and reflected ones above it. Inline so that callers build the ray in place:
// returned through memory from scene.cpp, its doubles were stored one by one and reloaded in pairs, a
// store-forwarding stall that held 12% of PathTracer::Li's profile (issue 17).
inline Ray Scene::spawnRay(const Intersection &its, const Vec3 &d) const {
    const double eps = epsilonAt(its.p);
    return Ray(its.p + its.n * (dot(its.n, d) >= 0 ? eps : -eps), d);
}

}  // namespace pf
