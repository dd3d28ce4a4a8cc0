// A connection strategy the path tracer runs at its non-specular vertices, which estimates a set of paths
// on its own: specular manifold sampling (integrators/sms_connection.h) connects a receiver x_1 to an
// emitter through a chain of one up to chainLength() specular vertices. The path tracer must then leave exactly
// those paths out of its own estimators, so that together they estimate every path once (the partition of path
// space that replaces MIS in SMS, ALGORITHMS.md §7.1 "MIS with standard strategies remains open"):
//
//   the strategy estimates x_1 -> y_1 -> … -> y_k -> x_e where x_1 is a vertex it runs at (receives()) with a
//   budget of b = min(chainLength(), maxDepth - depth(x_1) - 1) >= 1 vertices, 1 <= k <= b, x_1 -> y_1 was
//   sampled by a smooth (non-delta) lobe of x_1, each y_j is the first surface on the ray that left its
//   predecessor and casts() with the lobe it scattered by, and x_e is the first surface after y_k, on an
//   emitter it connectsTo(). estimate() gets b and must estimate exactly these paths.
//
// Every other path stays with the path tracer: dielectric reflections on a refracting caster, chains
// longer than b, chains through a non-caster, emitters SMS does not connect to, delta lobes of x_1,
// index-matched crossings in between. This is where the reference code loses light (SMS_PORTAL_NOTES.md §1.2): it skips
// emitter hits after any caster vertex whatever the flags of the receiver and emitter.
#pragma once
#include <cstdint>

#include "core/sampler.h"
#include "core/spectrum.h"

namespace pf {

class Emitter;
class Scene;
struct Intersection;

class CausticConnection {
public:
    virtual ~CausticConnection() = default;
    // The scene's flags (throws SceneError).
    virtual void check(const Scene &scene) const = 0;
    // Before a render: resets the statistics.
    virtual void begin() const = 0;
    // After a render: reports the statistics.
    virtual void end() const = 0;
    virtual bool receives(const Intersection &its) const = 0;
    // The longest chain the strategy connects through (the bound on k above).
    virtual int chainLength() const = 0;
    // The radiance reaching receiver its (its.wi faces the previous vertex) through the paths above of at
    // most `budget` specular vertices, with the receiver's BSDF and cosine included.
    virtual Spectrum estimate(const Scene &scene, Sampler &sampler, const Intersection &its, int budget) const = 0;
    virtual bool casts(const Intersection &its, uint32_t sampledLobe) const = 0;
    virtual bool connectsTo(const Emitter &emitter) const = 0;
};

}  // namespace pf
