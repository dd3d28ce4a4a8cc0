// Path tracer (`path`, and with participating media `volpath`) with next-event estimation from surface and medium
// vertices and multiple importance sampling (power heuristic) against BSDF and phase-function sampling, following
// Mitsuba 0.6's volpath (MIVolumetricPathTracer) and the path-space view of ALGORITHMS.md §1.1: a medium vertex
// scatters with sigma_s * phase, and every edge carries the transmittance tau.
//
// * Free-flight sampling decides, on each segment, between a medium interaction and reaching the next
//   surface; the throughput is divided by the medium's pdfSuccess or pdfFailure, so chromatic media stay
//   unbiased (medium/homogeneous.cpp).
// * Emitters reached by a sampled direction are found by walking the direction through index-matched
//   surfaces and media with the analytic transmittance (walkTransmittance), exactly as next-event
//   estimation's shadow rays do, so the two strategies estimate the same paths and the MIS weights are
//   those of the direction densities. The path itself then continues with free-flight sampling, and
//   emission it meets later is not counted again.
// * Depth counts path segments as Mitsuba 0.6 does (1 = directly visible emitters, 2 = single
//   scattering, -1 = unbounded), and a pass through a Null lobe (an index-matched boundary, the
//   transparent part of a mask or thin dielectric) counts as one, like a scattering event: Mitsuba's
//   path, volpath and volpath_simple all advance their depth at such a crossing (volpath: "rRec.depth++"
//   in its ENull branch), and their shadow rays and emitter searches from a vertex at depth d cross at
//   most maxDepth - d - 1 of them (the `interactions` of sampleAttenuatedEmitterDirect and
//   rayIntersectAndLookForEmitter). So a path contributes iff its segments plus its crossings are at
//   most maxDepth, the rule README.md states for every integrator. Russian roulette uses the same depth
//   (volpath: "rRec.depth++ >= m_rrDepth" after each scattering event, the crossings counted).
// * `path` is this estimator with media ignored (Mitsuba's path tracer does not render media): every
//   segment is vacuum and index-matched boundaries are plain pass-through.
// * With a caustic connection strategy (`sms`), the strategy runs at every non-specular vertex it receives
//   at, and the emitter hits of the paths it estimates are left out here (caustic_connection.h).
#include "integrators/path.h"

#include <algorithm>
#include <new>

#include "bsdf/bsdf.h"
#include "integrators/visibility.h"
#include "scene/crossings.h"
#include "scene/medium.h"
#include "scene/scene.h"

namespace pf {

namespace {

// How many index-matched surfaces a shadow ray or emitter search from a vertex at `depth` may cross
// (Mitsuba's `interactions = maxDepth - depth - 1`): each crossing is one more segment of the path.
// Negative: any number (maxDepth = -1).
int crossingBudget(int maxDepth, int depth) { return maxDepth < 0 ? -1 : maxDepth - depth - 1; }

bool withinBudget(int crossings, int budget) { return budget < 0 || crossings <= budget; }

// Radiance arriving at `ref` along the sampled direction ray.d (ray leaves ref in `medium`): each
// emitter the direction reaches through at most `budget` index-matched surfaces contributes its
// radiance times the transmittance up to it, and the environment contributes if the direction leaves
// the scene within the budget. An emitter hit first (nothing crossed) that `leaveOut` connects to is left
// to that strategy.
Spectrum emissionAlong(const Scene &scene, const Ray &ray, const Vec3 &ref, const Medium *medium, bool trackMedia,
                       double dirPdf, bool delta, Intersection &next, int budget,
                       const CausticConnection *leaveOut = nullptr) {
    Spectrum L;
    if (!scene.hasPassThroughSurfaces() && !(trackMedia && medium)) {
        // The first surface ends the search (nothing to cross, no medium): one intersection, without the
        // walk's visitor calls (issue 17: this search runs at every vertex). The same sums as the walk's,
        // whose transmittance here is exactly 1.
        ::new (static_cast<void *>(&next)) Intersection();
        const bool hit = scene.intersect(ray, next);
        const Emitter *emitter = hit ? next.emitter() : nullptr;
        const bool left = emitter && leaveOut && leaveOut->connectsTo(*emitter);
        // After a miss `next` is still invalid, which stands for the environment.
        if ((!hit || (emitter && !left)) && withinBudget(0, budget))
            L += misWeightedEmission(scene, ray, next, ref, dirPdf, delta);
        return L;
    }
    int crossed = 0;  // surfaces passed before the one visited (every visited surface but a blocker is passed)
    const auto visit = [&](const Intersection &its, const Spectrum &T) {
        const Emitter *emitter = its.emitter();
        const bool left = leaveOut && crossed == 0 && emitter && leaveOut->connectsTo(*emitter);
        if (emitter && withinBudget(crossed, budget) && !left)
            L += T * misWeightedEmission(scene, ray, its, ref, dirPdf, delta);
        ++crossed;
    };
    const Spectrum escaped = walkTransmittance(scene, ray, medium, visit, trackMedia, &next);
    if (!escaped.isBlack() && withinBudget(crossed, budget))
        L += escaped * misWeightedEmission(scene, ray, Intersection(), ref, dirPdf, delta);
    return L;
}

// Next-event estimation's contribution for an emitter sample ds with weight `value` (radiance / pdf):
// the scattering value f towards ds.d, attenuated along `shadow` (which starts in `medium` and may cross
// at most `budget` index-matched surfaces), weighted against the scattering density scatterPdf of the
// same direction.
Spectrum directLight(const Scene &scene, const DirectSample &ds, const Spectrum &value, const Spectrum &f,
                     double scatterPdf, const Ray &shadow, const Medium *medium, bool trackMedia, int budget) {
    if (value.isBlack() || f.isBlack()) return {};
    Spectrum T;
    if (budget < 0 || !scene.hasPassThroughSurfaces()) {
        T = transmittance(scene, shadow, medium, trackMedia);
    } else {
        int crossed = 0;  // a shadow ray that is not blocked visits only surfaces it passes
        T = walkTransmittance(
            scene, shadow, medium, [&](const Intersection &, const Spectrum &) { ++crossed; }, trackMedia);
        if (!withinBudget(crossed, budget)) return {};
    }
    if (T.isBlack()) return {};
    return value * f * T * (ds.measure == Measure::Discrete ? 1.0 : powerHeuristic(ds.pdf, scatterPdf));
}

}  // namespace

std::unique_ptr<SamplingIntegrator> makeDirectComponent(const SourceLocation &loc, int64_t maxDepth) {
    Properties p(ObjectKind::Integrator, "volpath", loc);
    p.set("maxDepth", Properties::Type::Integer, maxDepth < 0 ? int64_t{2} : std::min<int64_t>(2, maxDepth), loc);
    return std::make_unique<PathTracer>(p, true);
}

PathTracer::PathTracer(const Properties &props, bool media, std::shared_ptr<const CausticConnection> caustics)
    : media_(media), caustics_(std::move(caustics)) {
    maxDepth_ = static_cast<int>(props.getInt("maxDepth", -1));
    rrDepth_ = static_cast<int>(props.getInt("rrDepth", 5));
    strictNormals_ = props.getBool("strictNormals", false);
    hideEmitters_ = props.getBool("hideEmitters", false);
    if (maxDepth_ < -1 || maxDepth_ == 0) props.fail("maxDepth", "must be -1 (unbounded) or at least 1");
    if (rrDepth_ < 1) props.fail("rrDepth", "must be at least 1");
}

void PathTracer::checkScene(const Scene &scene) const {
    if (caustics_) caustics_->check(scene);
}

Bitmap PathTracer::render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const {
    if (caustics_) {
        caustics_->check(scene);
        caustics_->begin();
    }
    Bitmap image = SamplingIntegrator::render(scene, opt, stats);
    if (caustics_) caustics_->end();
    return image;
}

Spectrum PathTracer::Li(const Scene &scene, Sampler &sampler, const Ray &primary) const {
    Spectrum L, throughput(1.0);
    Ray ray = primary;
    // Free-flight segments are measured from the true position of the last vertex or boundary crossing,
    // not from the spawned ray's offset origin, so that media are not thinned by the ray epsilon at
    // every boundary.
    Vec3 origin = primary.o;
    const Medium *medium = media_ ? scene.sensor().medium() : nullptr;
    Intersection its;
    scene.intersect(ray, its);
    MediumSample ms;
    const BSDFContext ctx;
    double eta = 1.0;  // accumulated relative IOR, for Russian roulette (Mitsuba's radiance scaling)
    int depth = 1, crossings = 0;
    // Before the first scattering event emission is counted where the path meets it; afterwards
    // emissionAlong has already counted it at the vertex that sampled the direction.
    bool scattered = false;
    // The caustic strategy's chain so far (caustic_connection.h): -1 outside one; else the number of caster
    // vertices since the receiver that ran the strategy and left by a smooth lobe, and that receiver's budget.
    int chained = -1, chainBudget = 0;

    for (;;) {
        // Free-flight sampling only where there is a medium: `path` never pays for its record or the
        // segment's length (a square root).
        bool interacts = false;
        if (medium) {
            ms = MediumSample();
            interacts = medium->sampleDistance(
                Ray(origin, ray.d, 0, its.isValid() ? (its.p - origin).length() : kInfinity), sampler.next1D(), ms);
        }
        if (interacts) {
            // Medium interaction: a scattering event with weight sigma_s * T / pdfSuccess.
            if (maxDepth_ >= 0 && depth >= maxDepth_) break;
            const int budget = crossingBudget(maxDepth_, depth);
            throughput *= ms.sigmaS * ms.transmittance / ms.pdfSuccess;
            chained = -1;  // a medium vertex breaks any caustic chain
            const PhaseFunction &phase = medium->phase();
            const Vec3 wi = -ray.d;

            DirectSample ds(ms.p, Vec3());
            const Spectrum value = scene.sampleEmitterDirect(ds, sampler.next2D());
            if (!value.isBlack())
                L += throughput * directLight(scene, ds, value, Spectrum(phase.eval(wi, ds.d)), phase.pdf(wi, ds.d),
                                              scene.spawnRayTo(ms.p, ds.p), medium, media_, budget);

            Vec3 wo;
            double phasePdf = 0;
            const double weight = phase.sample(wi, wo, phasePdf, sampler.next2D());
            if (!(weight > 0)) break;
            throughput *= weight;
            ray = Ray(ms.p, wo);
            origin = ms.p;
            L += throughput * emissionAlong(scene, ray, ms.p, medium, media_, phasePdf, false, its, budget);
        } else {
            if (medium) {
                if (!(ms.pdfFailure > 0)) break;
                throughput *= ms.transmittance / ms.pdfFailure;
            }
            if (!scattered && !hideEmitters_) {
                L += throughput *
                     (its.isValid() ? its.Le(-ray.d) : misWeightedEmission(scene, ray, its, ray.o, 0.0, true));
            }
            if (!its.isValid()) break;
            const BSDF *bsdf = its.bsdf();
            // At the depth limit even an index-matched boundary ends the path: crossing it would be one
            // segment more (Mitsuba: "if (rRec.depth >= m_maxDepth) break" before any sampling).
            if (maxDepth_ >= 0 && depth >= maxDepth_) break;
            const int budget = crossingBudget(maxDepth_, depth);
            const bool passOnly = bsdf->isNull();
            // Mitsuba's strictNormals: the geometric and shading normals must agree on the incident side.
            if (!passOnly && strictNormals_ && dot(ray.d, its.n) * Frame::cosTheta(its.wi) >= 0) break;

            const int chainAllowed = !caustics_      ? 0
                                     : maxDepth_ < 0 ? caustics_->chainLength()
                                                     : std::min(caustics_->chainLength(), maxDepth_ - depth - 1);
            const bool receiver =
                !passOnly && chainAllowed >= 1 && (bsdf->flags() & BSDFFlags::Smooth) && caustics_->receives(its);
            if (receiver) L += throughput * caustics_->estimate(scene, sampler, its, chainAllowed);
            DirectSample ds(its.p, its.n);
            Spectrum value, f;
            double bsdfPdf = 0;
            if (!passOnly && (bsdf->flags() & BSDFFlags::Smooth)) {
                value = scene.sampleEmitterDirect(ds, sampler.next2D());
                const Vec3 wo = its.toLocal(ds.d);
                if (!value.isBlack() && (!strictNormals_ || dot(ds.d, its.n) * Frame::cosTheta(wo) > 0))
                    f = bsdf->evalPdf(ctx, its, its.wi, wo, bsdfPdf);
            }
            // The next direction is sampled before the shadow ray is traced (its numbers still follow the
            // emitter's): the warp's chain of divisions, square roots and polynomials then runs while the
            // traversal starts, instead of after it while the next ray waits.
            BSDFSample bs;
            const double u1 = sampler.next1D();
            const BSDFContext sampleCtx(TransportMode::Radiance, passOnly ? BSDFFlags::Null : BSDFFlags::All);
            const Spectrum weight = bsdf->sample(sampleCtx, its, its.wi, bs, u1, sampler.next2D());
            if (!f.isBlack())
                L += throughput * directLight(scene, ds, value, f, bsdfPdf, scene.spawnRayTo(its, ds.p),
                                              media_ ? mediumAfter(its, ds.d, medium) : nullptr, media_, budget);
            if (weight.isBlack()) break;
            const Vec3 wo = its.toWorld(bs.wo);
            if (!passOnly && strictNormals_ && dot(wo, its.n) * Frame::cosTheta(bs.wo) <= 0) break;
            throughput *= weight;
            eta *= bs.eta;
            const bool leaveOut = chained >= 0 && chained < chainBudget && caustics_->casts(its, bs.sampledType);
            if (receiver && (bs.sampledType & BSDFFlags::Smooth) != 0) {
                chained = 0;
                chainBudget = chainAllowed;
            } else {
                chained = leaveOut ? chained + 1 : -1;
            }
            if (media_) medium = mediumAfter(its, wo, medium);
            origin = its.p;
            ray = scene.spawnRay(its, wo);
            if (bs.sampledType == BSDFFlags::Null) {
                // Passing straight through: not a scattering event, but one segment more (Mitsuba's
                // volpath: "rRec.depth++; continue", without Russian roulette). The emission beyond was
                // already counted from the previous vertex (its walks cross Null lobes within the same
                // budget), or will be counted by this loop if the path has not scattered yet.
                if (++crossings > kMaxCrossings) break;
                ++depth;
                its = Intersection();
                scene.intersect(ray, its);
                continue;
            }
            L += throughput * emissionAlong(scene, ray, origin, medium, media_, bs.pdf,
                                            (bs.sampledType & BSDFFlags::Delta) != 0, its, budget,
                                            leaveOut ? caustics_.get() : nullptr);
        }

        // `its` now holds the first surface along the sampled direction, found by emissionAlong.
        scattered = true;
        crossings = 0;
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
