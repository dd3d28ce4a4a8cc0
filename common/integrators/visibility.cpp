#include "integrators/visibility.h"

#include <new>

#include "bsdf/bsdf.h"
#include "scene/crossings.h"
#include "scene/medium.h"
#include "scene/scene.h"

namespace pf {

namespace {

// A walk whose first surface blocks whatever it is (no pass-through surfaces, no medium: the loop below would
// find its null transmittance zero) is one intersection found straight into `its`, without the loop's
// bookkeeping or a second Intersection to initialize (issue 17: `path`'s emitter search at every vertex).
Spectrum throughFirstSurface(const Scene &scene, const Ray &ray, const SurfaceVisitor *visit, Intersection &its) {
    ::new (static_cast<void *>(&its)) Intersection();
    if (!scene.intersect(ray, its)) return Spectrum(1.0);
    if (visit) (*visit)(its, Spectrum(1.0));
    return Spectrum(0.0);
}

// Medium segments run between the points where the walk meets surfaces (not the offset origins of the
// rays spawned there), so that media are not thinned by the ray epsilon at every crossing.
Spectrum walk(const Scene &scene, const Ray &first, bool trackMedia, const Medium *medium, const SurfaceVisitor *visit,
              Intersection *firstHit) {
    // Nothing to pass through and no medium to attenuate (transmittance() answers that case with a plain
    // occlusion query): the first surface ends the walk.
    if (!scene.hasPassThroughSurfaces() && !(trackMedia && medium)) {
        if (firstHit) return throughFirstSurface(scene, first, visit, *firstHit);
        Intersection local;
        return throughFirstSurface(scene, first, visit, local);
    }
    Ray ray = first;  // respawned at every crossing
    Spectrum T(1.0);
    Vec3 start = ray.o;
    Intersection local;
    for (int crossings = 0; crossings < kMaxCrossings; ++crossings) {
        // The first surface is found straight into *firstHit, reset in place: copying an Intersection
        // (some 300 bytes, a `rep movsq`) took half of this walk's time in the path tracer (issue 17's perf).
        Intersection &its = crossings == 0 && firstHit ? *firstHit : local;
        ::new (static_cast<void *>(&its)) Intersection();
        const bool hit = scene.intersect(ray, its);
        if (trackMedia && medium) {
            const double length = hit ? (its.p - start).length()
                                      : (std::isfinite(ray.tmax) ? (ray(ray.tmax) - start).length() : kInfinity);
            T *= medium->evalTransmittance(Ray(start, ray.d, 0, length));
        }
        if (!hit || T.isBlack()) return T;
        if (visit) (*visit)(its, T);
        T *= nullTransmittance(its);
        if (T.isBlack()) return T;
        if (trackMedia) medium = mediumAfter(its, ray.d, medium);
        start = its.p;
        ray = std::isfinite(ray.tmax) ? scene.spawnRayTo(its, ray(ray.tmax)) : scene.spawnRay(its, ray.d);
    }
    return Spectrum(0.0);
}

}  // namespace

Spectrum nullTransmittance(const Intersection &its) {
    const BSDF *bsdf = its.bsdf();
    if (!bsdf || !(bsdf->flags() & BSDFFlags::Null)) return Spectrum(0.0);
    const BSDFContext ctx(TransportMode::Radiance, BSDFFlags::Null);
    return bsdf->eval(ctx, its, its.wi, -its.wi, Measure::Discrete);
}

Spectrum walkedTransmittance(const Scene &scene, const Ray &ray, const Medium *medium, bool trackMedia) {
    return walk(scene, ray, trackMedia, medium, nullptr, nullptr);
}

Spectrum walkTransmittance(const Scene &scene, const Ray &ray, const Medium *medium, const SurfaceVisitor &visit,
                           bool trackMedia, Intersection *firstHit) {
    return walk(scene, ray, trackMedia, medium, &visit, firstHit);
}

const Medium *mediumAfter(const Intersection &its, const Vec3 &d, const Medium *current) {
    const Shape *shape = its.shape;
    return shape->interiorMedium() || shape->exteriorMedium() ? its.targetMedium(d) : current;
}

Spectrum misWeightedEmission(const Scene &scene, const Ray &ray, const Intersection &its, const Vec3 &ref,
                             double dirPdf, bool delta) {
    const Emitter *emitter = its.isValid() ? its.emitter() : scene.environment();
    if (!emitter) return {};
    const Spectrum Le = its.isValid() ? emitter->eval(its, -ray.d) : emitter->evalEnvironment(ray);
    if (Le.isBlack() || delta) return Le;
    DirectSample ds(ref, Vec3());
    ds.d = ray.d;
    ds.object = emitter;
    if (its.isValid()) {
        ds.p = its.p;
        ds.n = its.n;
        ds.uv = its.uv;
        ds.dist = (its.p - ref).length();
    } else {
        ds.dist = kInfinity;
    }
    return Le * powerHeuristic(dirPdf, scene.pdfEmitterDirect(ds, emitter));
}

}  // namespace pf
