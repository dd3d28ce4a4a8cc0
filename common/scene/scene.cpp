#include "scene/scene.h"

#include "bsdf/bsdf.h"
#include "shape/analytic.h"
#include "shape/instance.h"
#include "shape/shapegroup.h"

namespace pf {

namespace {

thread_local uint64_t tlRayCount = 0;
thread_local std::vector<Scene::TracedRay> *tlRayLog = nullptr;

template <class Convert>
void setOriginDirection(const Ray &r, RTCRay &e, Convert convert) {
    e.org_x = convert(r.o.x);
    e.org_y = convert(r.o.y);
    e.org_z = convert(r.o.z);
    e.dir_x = convert(r.d.x);
    e.dir_y = convert(r.d.y);
    e.dir_z = convert(r.d.z);
    e.tnear = convert(r.tmin);
}

// Origin, direction and tmin lie well inside float range on every ray in practice (only tmax is often
// infinite), so one test of their largest magnitude lets them convert directly, with the same bits as
// toEmbreeFloat's saturating conversion; seven of those took some 60 instructions a ray (issue 17). A NaN
// drops out of the maximum and converts to NaN either way.
void toEmbree(const Ray &r, RTCRay &e) {
    const double largest = std::max({std::abs(r.o.x), std::abs(r.o.y), std::abs(r.o.z), std::abs(r.d.x),
                                     std::abs(r.d.y), std::abs(r.d.z), std::abs(r.tmin)});
    if (largest <= std::numeric_limits<float>::max())
        setOriginDirection(r, e, [](double v) { return static_cast<float>(v); });
    else
        setOriginDirection(r, e, toEmbreeFloat);
    e.tfar = toEmbreeFloat(r.tmax);
    e.time = 0.0f;
    e.mask = 0xFFFFFFFFu;
    e.id = 0;
    e.flags = 0;
}

// Ray from `from` towards p, ending targetEps before it and a relative kShadowEpsilon earlier still.
Ray rayTowards(const Vec3 &from, const Vec3 &p, double tmin, double targetEps) {
    const Vec3 d = p - from;
    const double dist = d.length();
    if (!(dist > 0)) return Ray(from, Vec3(0, 0, 1), tmin, tmin);
    return Ray(from, d / dist, tmin, dist * (1.0 - kShadowEpsilon) - targetEps);
}

}  // namespace

Scene::Scene() {
    device_ = rtcNewDevice(nullptr);
    if (!device_)
        throw SceneError("cannot create the Embree device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
}

Scene::~Scene() {
    if (rtc_) rtcReleaseScene(rtc_);
    rtcReleaseDevice(device_);
}

// Shape groups are only rendered through their instances, and an instance contributes its transformed
// copies of the group's shapes (shape/shapegroup.h).
void Scene::addShape(std::shared_ptr<Shape> shape) {
    if (dynamic_cast<const ShapeGroup *>(shape.get())) return;
    if (const auto *instance = dynamic_cast<const Instance *>(shape.get())) {
        for (const auto &part : instance->parts()) addShape(part);
        return;
    }
    if (shape->emitterPtr()) emitters_.push_back(shape->emitterPtr());
    shapes_.push_back(std::move(shape));
}

void Scene::addEmitter(std::shared_ptr<Emitter> emitter) {
    const auto companions = emitter->companions();
    emitters_.push_back(std::move(emitter));
    for (auto &c : companions) addEmitter(c);
}

void Scene::finalize() {
    if (!sensor_) throw SceneError(location(), "the scene has no sensor");
    if (shapes_.empty() && emitters_.empty()) throw SceneError(location(), "the scene has no shapes and no emitters");

    if (rtc_) rtcReleaseScene(rtc_);
    rtc_ = rtcNewScene(device_);
    // Robust traversal: no hit is lost to the fast, slightly non-conservative box and triangle tests.
    rtcSetSceneFlags(rtc_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(rtc_, RTC_BUILD_QUALITY_HIGH);
    geomToShape_.clear();
    bounds_ = AABB();
    passThrough_ = false;
    for (const auto &shape : shapes_) {
        passThrough_ |= shape->bsdf() && (shape->bsdf()->flags() & BSDFFlags::Null);
        const unsigned id = shape->addToEmbree(device_, rtc_);
        if (id >= geomToShape_.size()) geomToShape_.resize(id + 1, nullptr);
        geomToShape_[id] = shape.get();
        bounds_.expand(shape->bbox());
    }
    rtcCommitScene(rtc_);
    if (const RTCError err = rtcGetDeviceError(device_); err != RTC_ERROR_NONE)
        throw SceneError(location(), "Embree could not build the scene (error " + std::to_string(err) + ")");
    // A scene of emitters alone is bounded by the sensor's position.
    if (!bounds_.valid()) bounds_.expand(sensor_->toWorld().point(Vec3(0.0)));

    environment_ = nullptr;
    std::vector<double> weights;
    for (const auto &e : emitters_) {
        // Escaping rays see one environment; delta lights at infinity (directional) cannot be hit, so they
        // may sit beside it, as in Mitsuba (a sky with a directional sun).
        if (e->isEnvironment() && !e->isDelta()) {
            if (environment_) throw SceneError(e->location(), "only one environment emitter is supported");
            environment_ = e.get();
        }
        weights.push_back(e->samplingWeight());
    }
    for (const auto &e : emitters_) e->configure(*this);
    sensor_->configure(*this);
    emitterDist_ = Distribution1D(weights);
}

namespace {

void embreeIntersect(RTCScene scene, const Ray &ray, RTCRayHit &rh) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    toEmbree(ray, rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    const ScopedQueryRay exact(ray);
    rtcIntersect1(scene, &ctx, &rh);
}

// Embree marks an occluded ray with tfar = -inf.
bool embreeOccluded(RTCScene scene, const Ray &ray) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRay r;
    toEmbree(ray, r);
    const ScopedQueryRay exact(ray);
    rtcOccluded1(scene, &ctx, &r);
    return r.tfar < 0;
}

}  // namespace

void Scene::recordThreadRays(std::vector<TracedRay> *log) { tlRayLog = log; }

bool Scene::traverse(const TracedRay &r) const {
    if (r.shadow) return embreeOccluded(rtc_, r.ray);
    RTCRayHit rh;
    embreeIntersect(rtc_, r.ray, rh);
    return rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
}

bool Scene::intersect(const Ray &ray, Intersection &its) const {
    ++tlRayCount;
    if (tlRayLog) tlRayLog->push_back({ray, false});
    RTCRayHit rh;
    embreeIntersect(rtc_, ray, rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    geomToShape_[rh.hit.geomID]->fillIntersection(ray, rh.ray.tfar, rh.hit.primID, Vec2(rh.hit.u, rh.hit.v), its);
    its.wi = its.toLocal(-normalize(ray.d));
    return true;
}

bool Scene::occluded(const Ray &ray) const {
    ++tlRayCount;
    if (tlRayLog) tlRayLog->push_back({ray, true});
    return embreeOccluded(rtc_, ray);
}

// Shadow rays stop short of the target by its own offset (the target usually lies on a surface too) and
// by a relative kShadowEpsilon, which absorbs the error of a surface met at a grazing angle.
Ray Scene::spawnRayTo(const Intersection &its, const Vec3 &p) const {
    return rayTowards(spawnRay(its, p - its.p).o, p, 0.0, epsilonAt(p));
}

// A point without a surface (sensor aperture, medium) gets its offset as tmin instead.
Ray Scene::spawnRayTo(const Vec3 &from, const Vec3 &p) const {
    return rayTowards(from, p, epsilonAt(from), epsilonAt(p));
}

Spectrum Scene::sampleEmitterDirect(DirectSample &ds, const Vec2 &u) const {
    ds.pdf = 0;
    if (emitterDist_.empty()) return Spectrum(0.0);
    double pmf, ux;
    const size_t i = emitterDist_.sampleDiscrete(u.x, &pmf, &ux);
    const Emitter *emitter = emitters_[i].get();
    const Spectrum value = emitter->sampleDirect(ds, Vec2(ux, u.y));
    ds.object = emitter;
    if (!(ds.pdf > 0)) return Spectrum(0.0);
    ds.pdf *= pmf;
    return value / pmf;
}

double Scene::pdfEmitterDirect(const DirectSample &ds, const Emitter *emitter) const {
    return emitter ? emitter->pdfDirect(ds) * emitterPmf(emitter) : 0.0;
}

const Emitter *Scene::sampleEmitter(double u, double &pmf) const {
    pmf = 0;
    if (emitterDist_.empty()) return nullptr;
    return emitters_[emitterDist_.sampleDiscrete(u, &pmf)].get();
}

// Selection is proportional to samplingWeight, so the probability needs no lookup of the emitter.
double Scene::emitterPmf(const Emitter *e) const {
    return e && !emitterDist_.empty() ? e->samplingWeight() / emitterDist_.sum() : 0.0;
}

uint64_t Scene::threadRayCount() { return tlRayCount; }

size_t Scene::primitiveCount() const {
    size_t n = 0;
    for (const auto &s : shapes_) n += s->primitiveCount();
    return n;
}

}  // namespace pf
