#include "path/edge.h"

#include "integrators/visibility.h"
#include "scene/crossings.h"
#include "scene/medium.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The medium segments of one edge (between the surfaces it crosses) and what each walk pays for them
// (ALGORITHMS.md §1.4): a walk crosses every segment on its way and, when the edge ends at a medium
// vertex, stops in the last segment it enters. The two walks enter the edge from opposite ends.
class SegmentDensities {
public:
    void add(const Medium *medium, const Ray &segment, double failure) {
        if (count_++ == 0) {
            first_ = {medium, segment, failure};
        } else {
            exceptFirst_ *= failure;
            exceptLast_ *= last_.failure;
        }
        last_ = {medium, segment, failure};
    }
    // The walk that traced the edge: it ends at the far end, in a medium or on a surface.
    double forward(bool endInMedium) const {
        return exceptLast_ * (endInMedium ? stopDensity(last_, true) : last_.failure);
    }
    // The walk coming from the far end, ending at the start.
    double reverse(bool startInMedium) const {
        return exceptFirst_ * (startInMedium ? stopDensity(first_, false) : first_.failure);
    }

private:
    struct Segment {
        const Medium *medium = nullptr;
        Ray ray;
        double failure = 1.0;
    };
    // Density per unit length of a free flight stopping at the segment's far end (or, for the reverse
    // walk, at its near end). A point in vacuum cannot be a medium vertex.
    static double stopDensity(const Segment &s, bool atFarEnd) {
        if (!s.medium) return 0.0;
        MediumSample ms;
        s.medium->evalDistancePdf(s.ray, true, ms);
        return atFarEnd ? ms.pdfSuccess : ms.pdfSuccessRev;
    }

    Segment first_, last_;
    int count_ = 0;
    double exceptFirst_ = 1.0, exceptLast_ = 1.0;
};

enum class WalkEnd { Surface, Medium, Escaped, Reached, Blocked };

double failureProbability(const Medium &medium, const Ray &segment) {
    MediumSample ms;
    medium.evalDistancePdf(segment, false, ms);
    return ms.pdfFailure;
}

// The walk behind both operations. With a sampler (SampleNext) each medium segment samples a free
// flight, and the walk stops at an interaction, at the first surface that is not index-matched, or when
// it leaves the scene. With a target (Connect) it must reach the target. Medium segments run between the
// points where the walk meets surfaces, not the offset origins of the spawned rays (as in visibility.cpp).
// `its` (cleared by the caller) receives each surface met.
WalkEnd walk(const Scene &scene, Sampler *sampler, Ray ray, Vec3 start, const Medium *medium, const Vec3 *target,
             Spectrum &T, SegmentDensities &densities, EdgeEnd &end, Intersection &its, int &crossings) {
    for (crossings = 0; crossings < kMaxCrossings; ++crossings) {
        if (crossings > 0) its = Intersection();
        const bool hit = scene.intersect(ray, its);
        const double length = hit ? (its.p - start).length() : target ? (*target - start).length() : kInfinity;
        const Ray segment(start, ray.d, 0.0, length);
        if (!medium) {
            densities.add(nullptr, segment, 1.0);
        } else if (sampler) {
            MediumSample ms;
            const bool interaction = medium->sampleDistance(segment, sampler->next1D(), ms);
            T *= ms.transmittance;
            if (interaction) {
                const Ray stopped(start, ray.d, 0.0, ms.t);
                densities.add(medium, stopped, failureProbability(*medium, stopped));
                end.kind = EdgeEnd::Kind::Medium;
                end.p = ms.p;
                end.medium = medium;
                return WalkEnd::Medium;
            }
            densities.add(medium, segment, ms.pdfFailure);
        } else {
            T *= medium->evalTransmittance(segment);
            densities.add(medium, segment, failureProbability(*medium, segment));
        }
        if (!hit) {
            if (target) return WalkEnd::Reached;
            end.kind = EdgeEnd::Kind::Escaped;
            end.lastRay = ray;
            end.medium = medium;
            return WalkEnd::Escaped;
        }
        const BSDF *bsdf = its.bsdf();
        if (!bsdf || !bsdf->isNull()) {
            if (target) return WalkEnd::Blocked;
            end.kind = EdgeEnd::Kind::Surface;
            end.medium = medium;
            return WalkEnd::Surface;
        }
        T *= nullTransmittance(its);
        if (T.isBlack()) return WalkEnd::Blocked;
        medium = mediumAfter(its, ray.d, medium);
        start = its.p;
        ray = target ? scene.spawnRayTo(its, *target) : scene.spawnRay(its, ray.d);
    }
    return WalkEnd::Blocked;
}

void fillEdge(PathEdge &edge, const Medium *medium, const Vec3 &d, const Spectrum &T, const SegmentDensities &densities,
              bool startInMedium, bool endInMedium, TransportMode mode, int crossings) {
    edge.crossings = crossings;
    edge.medium = medium;
    edge.d = d;
    edge.transmittance = T;
    edge.pdf[modeIndex(mode)] = densities.forward(endInMedium);
    edge.pdf[modeIndex(otherMode(mode))] = densities.reverse(startInMedium);
}

}  // namespace

EdgeEnd traceEdge(const Scene &scene, Sampler &sampler, Ray ray, const Vec3 &start, const Medium *medium,
                  bool startInMedium, TransportMode mode, PathEdge &edge, Intersection &hit) {
    EdgeEnd end;
    Spectrum T(1.0);
    SegmentDensities densities;
    int crossings = 0;
    const WalkEnd result = walk(scene, &sampler, ray, start, medium, nullptr, T, densities, end, hit, crossings);
    if (result == WalkEnd::Blocked) T = Spectrum(0.0);
    fillEdge(edge, medium, ray.d, T, densities, startInMedium, result == WalkEnd::Medium, mode, crossings);
    return end;
}

bool connectEdge(const Scene &scene, Ray ray, const Vec3 &start, const Vec3 &target, const Medium *medium,
                 bool startInMedium, bool endInMedium, TransportMode mode, PathEdge &edge) {
    Spectrum T(1.0);
    SegmentDensities densities;
    int crossings = 0;
    if (!medium && !scene.hasPassThroughSurfaces()) {
        // In vacuum through a scene without pass-through surfaces there is nothing to cross: an occlusion
        // query answers, without a hit's surface point and frame (issue 17).
        if (scene.occluded(ray)) return false;
        densities.add(nullptr, Ray(start, ray.d, 0.0, (target - start).length()), 1.0);
    } else {
        EdgeEnd unused;
        Intersection its;
        if (walk(scene, nullptr, ray, start, medium, &target, T, densities, unused, its, crossings) != WalkEnd::Reached)
            return false;
    }
    fillEdge(edge, medium, ray.d, T, densities, startInMedium, endInMedium, mode, crossings);
    edge.length = (target - start).length();
    return !T.isBlack();
}

}  // namespace pf
