#include "path/perturbation.h"

#include "bsdf/bsdf.h"
#include "core/frame.h"
#include "core/sincos.h"
#include "integrators/visibility.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The angle between two unit vectors: atan2 of |cross| and dot keeps small angles accurate, where
// acos(dot) loses half the digits.
double angleBetween(const Vec3 &a, const Vec3 &b) { return std::atan2(cross(a, b).length(), dot(a, b)); }

}  // namespace

ReciprocalKernel::ReciprocalKernel(double lo, double hi) : lo_(lo), hi_(hi), logRatio_(std::log(hi / lo)) {}

double ReciprocalKernel::sample(double u) const { return lo_ * std::exp(logRatio_ * u); }

double ReciprocalKernel::pdf(double r) const { return r >= lo_ && r <= hi_ ? 1.0 / (r * logRatio_) : 0.0; }

Vec2 ReciprocalKernel::sampleOffset(const Vec2 &u) const {
    const double r = sample(u.x);
    const SinCos phi = sinCos2Pi(u.y);
    return {r * phi.cos, r * phi.sin};
}

double ReciprocalKernel::offsetPdf(const Vec2 &offset) const {
    const double r = std::hypot(offset.x, offset.y);
    return r > 0 ? pdf(r) / (2 * kPi * r) : 0.0;
}

Vec3 ReciprocalKernel::sampleDirection(const Vec3 &axis, const Vec2 &u) const {
    const double theta = sample(u.x);
    const SinCos phi = sinCos2Pi(u.y);
    const double sinTheta = std::sin(theta);
    return Frame(axis).toWorld(Vec3(sinTheta * phi.cos, sinTheta * phi.sin, std::cos(theta)));
}

double ReciprocalKernel::directionPdf(const Vec3 &axis, const Vec3 &d) const {
    const double theta = angleBetween(axis, d);
    return theta > 0 ? pdf(theta) / (2 * kPi * std::sin(theta)) : 0.0;
}

PerturbationScale::PerturbationScale(const Scene &scene) {
    const Sensor &sensor = scene.sensor();
    const Film &film = sensor.film();
    const double width = film.cropWidth(), height = film.cropHeight();
    filmArea = width * height;
    r2 = std::sqrt(0.05 * filmArea / kPi);
    // The angle between the rays through the centre of the image and one pixel to the side or down.
    const Vec2 centre(width / 2, height / 2), lensCentre(0.5, 0.5);
    Ray c, dx, dy;
    sensor.sampleRay(c, centre, lensCentre);
    sensor.sampleRay(dx, centre + Vec2(1, 0), lensCentre);
    sensor.sampleRay(dy, centre + Vec2(0, 1), lensCentre);
    radiansPerPixel = std::min(angleBetween(c.d, dx.d), angleBetween(c.d, dy.d));
}

namespace {

// Both directions on the side of the surface where geometric and shading normal agree (vertex.cpp).
bool sameSide(const Intersection &its, const Vec3 &wLocal) { return dot(its.toWorld(wLocal), its.n) * wLocal.z > 0; }

// The Dirac lobe that x's specular vertex v was crossed through.
uint32_t diracLobe(const PathVertex &v) {
    return v.its.wi.z * v.woLocal.z > 0 ? BSDFFlags::DeltaReflection : BSDFFlags::DeltaTransmission;
}

}  // namespace

const Medium *mediumAt(const Scene &scene, const PathVertex &from, const Vec3 &p) {
    const Vec3 d = normalize(p - from.position());
    const Medium *medium = from.mediumToward(d);
    const bool onSurface = from.its.shape && (from.type == VertexType::Surface || from.type == VertexType::EmitterNode);
    const Ray ray = onSurface ? scene.spawnRayTo(from.its, p) : scene.spawnRayTo(from.position(), p);
    // Each index-matched boundary on the way switches to the medium on its far side (media are not attenuated
    // here: only which one p lies in matters).
    const auto cross = [&](const Intersection &its, const Spectrum &) { medium = mediumAfter(its, d, medium); };
    return walkTransmittance(scene, ray, nullptr, cross, false).isBlack() ? nullptr : medium;
}

bool placeHeld(const Scene &scene, TransportMode mode, const PathVertex &from, const Vec3 &d, double held,
               PathEdge &edge, PathVertex &succ) {
    succ = PathVertex();
    succ.type = VertexType::Medium;
    succ.its.p = from.position() + d * held;
    succ.its.wi = -d;
    succ.medium = mediumAt(scene, from, succ.its.p);
    succ.walkMode = mode;
    if (!succ.medium) return false;
    const bool up = mode == TransportMode::Importance;
    return connect(scene, up ? from : succ, up ? succ : from, edge);
}

bool propagate(const Scene &scene, Sampler &sampler, TransportMode mode, const PathView &x, MutablePath &y, int from,
               int to, Vec3 d, double held) {
    const int dir = to > from ? 1 : -1;
    for (int cur = from;; cur += dir) {
        const int next = cur + dir;
        const PathVertex &expected = x.vertex(next);
        // Built in y itself (perturb() and placeHeld() overwrite both whole; a failed proposal is not used)
        // instead of copying a 496-byte vertex per step (issue 17).
        PathVertex &succ = y.vertex(next);
        PathEdge &edge = y.edge(std::min(cur, next));
        if (next == to && held > 0) return placeHeld(scene, mode, y.vertex(cur), d, held, edge, succ);
        if (!y.vertex(cur).perturb(scene, sampler, mode, d, edge, succ) || succ.isEndpointNode()) return false;
        const bool surfaceExpected = expected.type == VertexType::Surface || expected.type == VertexType::EmitterNode;
        if ((succ.type == VertexType::Surface) != surfaceExpected) return false;
        if (next == to) return true;
        // A specular vertex: continue through the same kind of Dirac lobe.
        const uint32_t lobe = diracLobe(expected);
        if (succ.type != VertexType::Surface || !(succ.its.bsdf()->flags() & lobe) || !sameSide(succ.its, succ.its.wi))
            return false;
        BSDFSample bs;
        if (succ.its.bsdf()
                ->sample(BSDFContext(mode, lobe), succ.its, succ.its.wi, bs, 0.5, Vec2(0.5, 0.5))
                .isBlack() ||
            !sameSide(succ.its, bs.wo))
            return false;
        succ.delta = true;
        succ.woLocal = bs.wo;
        d = succ.its.toWorld(bs.wo);
    }
}

Vec3 unitDirection(const PathVertex &from, const PathVertex &to) { return normalize(to.position() - from.position()); }

Vec3 rayDirection(const Scene &scene, const PathVertex &from, const PathVertex &to) {
    const bool onSurface = from.its.shape && (from.type == VertexType::Surface || from.type == VertexType::EmitterNode);
    const Vec3 origin = onSurface ? scene.spawnRay(from.its, unitDirection(from, to)).o : from.position();
    return normalize(to.position() - origin);
}

double propagationJacobian(const PathView &y, int from, int to, TransportMode mode) {
    const int dir = to > from ? 1 : -1;
    double factor = 1.0;
    for (int cur = from; cur != to; cur += dir) {
        const PathVertex &a = y.vertex(cur), &b = y.vertex(cur + dir);
        const Vec3 ab = b.position() - a.position();
        const double dist2 = ab.lengthSquared();
        factor *= b.cosine(ab / std::sqrt(dist2)) / dist2 * y.edge(std::min(cur, cur + dir)).pdf[modeIndex(mode)];
    }
    return factor;
}

SensorChains sensorChains(const PathView &x) {
    int chains = 1;
    for (int j = x.length() - 2; j >= 0; --j) {
        if (!isNonSpecular(x.vertex(j))) continue;
        if (j == 0) {
            const PathVertex &emitter = x.vertex(0);
            if (emitter.type != VertexType::EmitterNode || emitter.hasDeltaPosition() || !emitter.its.shape) return {};
            return {0, chains};
        }
        if (isNonSpecular(x.vertex(j - 1))) return {j, chains};
        ++chains;
    }
    return {};
}

namespace {

bool onFilm(const Film &film, const Vec2 &raster) {
    return raster.x >= 0 && raster.y >= 0 && raster.x < film.cropWidth() && raster.y < film.cropHeight();
}

// The next non-specular vertex of x below `cur`.
int nextNonSpecular(const PathView &x, int cur) {
    int j = cur - 1;
    while (!isNonSpecular(x.vertex(j))) --j;
    return j;
}

}  // namespace

bool sampleSensorCascade(const Scene &scene, Sampler &sampler, const ReciprocalKernel &offset,
                         const ReciprocalKernel *angle, const MutablePath &x, const SensorChains &chains,
                         MutablePath &y) {
    const int n = x.length(), b = chains.b;
    const Vec2 raster = x.raster() + offset.sampleOffset(sampler.next2D());
    if (!onFilm(scene.sensor().film(), raster)) return false;
    y = x;
    PathVertex &sensor = y.vertex(n - 1);
    DirectionSample ds;
    PositionSample ps = sensor.ps;
    if (scene.sensor().sampleDirection(ds, ps, raster).isBlack()) return false;
    sensor.ps.uv = raster;
    Vec3 d = ds.d;
    for (int cur = n - 1;;) {
        const int next = nextNonSpecular(x, cur);
        if (!propagate(scene, sampler, TransportMode::Radiance, x, y, cur, next, d)) return false;
        if (next == b) break;
        // Multi-chain: perturb the direction towards the next specular chain around the old one.
        d = angle->sampleDirection(rayDirection(scene, x.vertex(next), x.vertex(next - 1)), sampler.next2D());
        cur = next;
    }
    return connectJunction(scene, y, b - 1);
}

double sensorCascadeDensity(const Scene &scene, const ReciprocalKernel &offset, const ReciprocalKernel *angle,
                            const PerturbationScale &scale, const PathView &x, const PathView &y) {
    const SensorChains cx = sensorChains(x), cy = sensorChains(y);
    const int n = x.length();
    // The lens perturbation applies to one chain, the multi-chain perturbation to more.
    const bool applies = angle ? cx.chains >= 2 : cx.chains == 1;
    if (!applies || cx.b != cy.b || cx.chains != cy.chains || y.length() != n) return 0.0;
    const Vec2 &rasterX = x.vertex(n - 1).ps.uv, &rasterY = y.vertex(n - 1).ps.uv;
    // Uniform raster positions give the sensor's direction density; an offset density p per unit film
    // area is p * filmArea times that.
    double density = offset.offsetPdf(rasterY - rasterX) * scale.filmArea *
                     y.vertex(n - 1).evalPdf(scene, nullptr, y.vertex(n - 2), y.edge(n - 2), TransportMode::Radiance);
    for (int j = n - 2; j > cx.b && density > 0; --j) {
        if (!y.vertex(j).delta)
            density *= angle->directionPdf(rayDirection(scene, x.vertex(j), x.vertex(j - 1)),
                                           rayDirection(scene, y.vertex(j), y.vertex(j - 1)));
        density *= propagationJacobian(y, j, j - 1, TransportMode::Radiance);
    }
    return density;
}

}  // namespace pf
