// Unidirectional path tracer with next-event estimation and multiple importance sampling (power
// heuristic), Russian roulette and Mitsuba 0.6's maxDepth/rrDepth/strictNormals/hideEmitters semantics
// ([OV §3, Alg. 1], [TH 2.4.1-2.4.2]; ALGORITHMS.md §1.3; MIS: Veach 1997 §9.2).
//
// Depth counts path edges as in Mitsuba: depth 1 sees emitters directly, maxDepth = 2 is direct
// lighting only, -1 is unbounded. Passing through a Null lobe (index-matched surface) is not a
// scattering event and does not count.
#include "bsdf/bsdf.h"
#include "integrators/path.h"
#include "integrators/visibility.h"
#include "scene/scene.h"

namespace pf {

PathTracer::PathTracer(const Properties &props) {
    maxDepth_ = static_cast<int>(props.getInt("maxDepth", -1));
    rrDepth_ = static_cast<int>(props.getInt("rrDepth", 5));
    strictNormals_ = props.getBool("strictNormals", false);
    hideEmitters_ = props.getBool("hideEmitters", false);
    if (maxDepth_ < -1 || maxDepth_ == 0) props.fail("maxDepth", "must be -1 (unbounded) or at least 1");
    if (rrDepth_ < 1) props.fail("rrDepth", "must be at least 1");
}

// Radiance emitted towards the previous vertex by the surface or environment found along `ray`
// (its invalid = escaped), MIS-weighted against next-event estimation from `ref`.
Spectrum PathTracer::emitted(const Scene &scene, const Ray &ray, const Intersection &its, const Vec3 &ref,
                             double bsdfPdf, bool deltaSample) const {
    const Emitter *emitter = its.isValid() ? its.emitter() : scene.environment();
    if (!emitter) return {};
    const Spectrum Le = its.isValid() ? emitter->eval(its, -ray.d) : emitter->evalEnvironment(ray);
    if (Le.isBlack() || deltaSample) return Le;
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
    const double lightPdf = scene.pdfEmitterDirect(ds, emitter);
    return Le * powerHeuristic(bsdfPdf, lightPdf);
}

Spectrum PathTracer::Li(const Scene &scene, Sampler &sampler, const Ray &primary) const {
    Spectrum L, throughput(1.0);
    Ray ray = primary;
    Intersection its;
    scene.intersect(ray, its);
    // Pass through index-matched surfaces in front of the camera.
    for (int guard = 0; its.isValid() && its.bsdf()->isNull() && guard < 256; ++guard) {
        ray = scene.spawnRay(its, ray.d);
        its = Intersection();
        scene.intersect(ray, its);
    }
    if (!hideEmitters_) L += emitted(scene, ray, its, ray.o, 0.0, true);

    double eta = 1.0;  // accumulated relative IOR, for Russian roulette (Mitsuba's radiance scaling)
    int depth = 1;
    // At depth d both next-event estimation and the emitter found by BSDF sampling complete paths of
    // d + 1 edges, so scattering happens only while d < maxDepth (Mitsuba's MIPathTracer).
    while (its.isValid() && (maxDepth_ < 0 || depth < maxDepth_)) {
        const BSDF *bsdf = its.bsdf();
        // Mitsuba's strictNormals: the geometric and shading normals must agree on the incident side.
        if (strictNormals_ && dot(ray.d, its.n) * Frame::cosTheta(its.wi) >= 0) break;

        // Next-event estimation.
        const BSDFContext ctx;
        if (bsdf->flags() & BSDFFlags::Smooth) {
            DirectSample ds(its.p, its.n);
            const Spectrum value = scene.sampleEmitterDirect(ds, sampler.next2D());
            if (!value.isBlack()) {
                const Vec3 wo = its.toLocal(ds.d);
                const Spectrum f = bsdf->eval(ctx, its, its.wi, wo);
                const bool geometryOk = !strictNormals_ || dot(ds.d, its.n) * Frame::cosTheta(wo) > 0;
                if (!f.isBlack() && geometryOk) {
                    const Spectrum T = transmittance(scene, scene.spawnRayTo(its, ds.p));
                    if (!T.isBlack()) {
                        const bool delta = ds.measure == Measure::Discrete;
                        const double bsdfPdf = delta ? 0.0 : bsdf->pdf(ctx, its, its.wi, wo);
                        L += throughput * value * f * T * (delta ? 1.0 : powerHeuristic(ds.pdf, bsdfPdf));
                    }
                }
            }
        }

        // BSDF sampling.
        BSDFSample bs;
        const double u1 = sampler.next1D();
        const Spectrum weight = bsdf->sample(ctx, its, its.wi, bs, u1, sampler.next2D());
        if (weight.isBlack()) break;
        const Vec3 wo = its.toWorld(bs.wo);
        if (strictNormals_ && dot(wo, its.n) * Frame::cosTheta(bs.wo) <= 0) break;
        throughput *= weight;
        eta *= bs.eta;
        const bool deltaSample = (bs.sampledType & BSDFFlags::Delta) != 0;
        const Vec3 ref = its.p;

        // Trace to the next scattering surface, crossing index-matched (Null) surfaces.
        ray = scene.spawnRay(its, wo);
        its = Intersection();
        scene.intersect(ray, its);
        for (int guard = 0; its.isValid() && its.bsdf()->isNull() && guard < 256; ++guard) {
            ray = scene.spawnRay(its, ray.d);
            its = Intersection();
            scene.intersect(ray, its);
        }
        L += throughput * emitted(scene, ray, its, ref, bs.pdf, deltaSample);
        ++depth;

        // Russian roulette after rrDepth (Mitsuba: survival probability from throughput and eta^2).
        if (depth > rrDepth_) {
            const double q = std::min(throughput.max() * eta * eta, 0.95);
            if (sampler.next1D() >= q) break;
            throughput *= 1.0 / q;
        }
    }
    return L;
}

}  // namespace pf
