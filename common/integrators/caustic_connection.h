// A connection strategy the path tracer runs at its non-specular vertices, which estimates a set of paths
// on its own: specular manifold sampling (integrators/sms_connection.h) connects a receiver x_1 to an
// emitter through one specular vertex. The path tracer must then leave exactly those paths out of its own
// estimators, so that together they estimate every path once (the partition of path space that replaces
// MIS in SMS, ALGORITHMS.md §7.1 "MIS with standard strategies remains open"):
//
//   the strategy estimates x_1 -> x_2 -> x_3 where x_1 is a vertex it runs at (receives(), and within the
//   depth limit), x_1 -> x_2 was sampled by a smooth (non-delta) lobe of x_1, x_2 is the first surface on
//   that ray and casts() with the lobe it scattered by, and x_3 is the first surface after x_2, on an
//   emitter it connectsTo().
//
// Every other path stays with the path tracer: dielectric reflections on a refracting caster, chains
// through two casters, emitters SMS does not connect to, delta lobes of x_1, index-matched crossings in
// between. This is where the reference code loses light (SMS_PORTAL_NOTES.md §1.2): it skips emitter hits
// after any caster vertex whatever the flags of the receiver and emitter.
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
    // The radiance reaching receiver its (its.wi faces the previous vertex) through the paths above,
    // with the receiver's BSDF and cosine included.
    virtual Spectrum estimate(const Scene &scene, Sampler &sampler, const Intersection &its) const = 0;
    virtual bool casts(const Intersection &its, uint32_t sampledLobe) const = 0;
    virtual bool connectsTo(const Emitter &emitter) const = 0;
};

}  // namespace pf
