// Path edges of the path-space abstraction layer ([TH A4]). An edge is the straight transport between two
// path vertices: it carries the medium it starts in, its length and its transmittance tau (media and
// index-matched surfaces crossed on the way; ALGORITHMS.md §1.1 folds tau into G), and the probabilities
// with which each random walk crosses it and stops as it does (free-flight sampling in media: §1.4, "times
// the probability of flying the whole distance d").
//
// Index-matched (Null) surfaces are not path vertices: the layer folds them into the edge that crosses
// them, so that no strategy connects at one (Mitsuba's bidirectional layer marks them unconnectable and
// collapses them, path.cpp "Collapse edges/vertices that were caused by BSDF::ENull interactions").
// Mitsuba still counts each as a vertex of the path for maxDepth and rrDepth; the edge keeps how many it
// crossed, so that pathDepth() (path.h) counts the same.
#pragma once
#include "bsdf/bsdf.h"
#include "core/sampler.h"
#include "core/spectrum.h"
#include "scene/intersection.h"

namespace pf {

class Medium;
class Scene;

// Per-direction fields are indexed by the walk that uses them (ALGORITHMS.md §1.4): the emitter walk
// carries importance and produces p->, the sensor walk carries radiance and produces p<-.
inline int modeIndex(TransportMode mode) { return mode == TransportMode::Importance ? 1 : 0; }
inline TransportMode otherMode(TransportMode mode) {
    return mode == TransportMode::Importance ? TransportMode::Radiance : TransportMode::Importance;
}

struct PathEdge {
    const Medium *medium = nullptr;  // medium at the edge's start, in the direction it was traced
    Vec3 d;                          // unit direction in which it was traced
    double length = 0;               // distance between its two vertices
    Spectrum transmittance{1.0};
    // [modeIndex(mode)]: probability that the walk of `mode` leaves its vertex on this edge and ends as
    // the edge does: crossing every medium segment, times the free-flight density per unit length when
    // it ends at a medium vertex. 1 in vacuum; the emitter walk goes from the light side to the sensor
    // side of the edge.
    double pdf[2] = {1.0, 1.0};
    int crossings = 0;  // index-matched surfaces crossed between the two vertices
};

// Where a traced edge ended.
struct EdgeEnd {
    enum class Kind { Surface, Medium, Escaped } kind = Kind::Escaped;
    Vec3 p;                          // Medium: the interaction point
    const Medium *medium = nullptr;  // medium the end lies in (for a surface: the one the ray arrived through)
    Ray lastRay;                     // Escaped: the ray that left the scene
};

// SampleNext's propagation ([TH A4]): follows `ray` (unit direction, leaving `start`, which lies in
// `medium`) through index-matched surfaces. In each medium segment the free-flight distance is sampled
// with one number from `sampler`, so the edge ends at a medium interaction, at the next surface that is
// not index-matched, or escapes. Fills the edge as traced by the walk of `mode`; `startInMedium` tells
// whether the start is a medium vertex (for the reverse density). The surfaces the walk meets are written
// to `hit`, which the caller passes cleared: at a Surface end it holds the surface reached, at the others
// whatever the walk met last. Written in place, a hit is not copied twice on its way into a vertex (issue
// 17: an Intersection is 304 bytes).
EdgeEnd traceEdge(const Scene &scene, Sampler &sampler, Ray ray, const Vec3 &start, const Medium *medium,
                  bool startInMedium, TransportMode mode, PathEdge &edge, Intersection &hit);

// Connect's visibility ([TH A4]): the segment from `start` to `target` along `ray` (as spawned by the
// scene, stopping short of the target), through index-matched surfaces and media, for the walk of
// `mode` going from start to target. Returns false when an opaque surface blocks it.
bool connectEdge(const Scene &scene, Ray ray, const Vec3 &start, const Vec3 &target, const Medium *medium,
                 bool startInMedium, bool endInMedium, TransportMode mode, PathEdge &edge);

}  // namespace pf
