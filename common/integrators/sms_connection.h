// Specular manifold sampling as the path tracer's caustic connection strategy (the `sms` integrator,
// ALGORITHMS.md §7.1, SMS_PORTAL_NOTES.md §1.2): at every non-specular vertex x_1 on a caustic receiver,
// one emitter point x_3 is drawn (uniformly among the caustic emitters, then by the emitter's position
// sampling), and for every caustic caster the solutions x_2 of x_1 -> x_2 -> x_3 are summed by
// manifold/sms.h with the contribution f(x_1) F(x_2) G(x_1 -> x_2 -> x_3) L_e(x_3) / p(x_3); with bounces = 2
// (and a depth budget for it) also the two-vertex chains x_1 -> x_2 -> x'_2 -> x_3 whose first vertex is on that
// caster and whose second is on a caster too, with F(x_2) F(x'_2) and G through both.
//
// Roles (XML booleans on shapes and emitters; Mitsuba 0.6 has none): causticCaster defaults to "the shape's
// BSDF is ideally specular" (manifold/sms.h's specularEvent), causticReceiver to "not a caster", and
// causticEmitter to true for emitters with a position (area, point, spot). A caster flag on a shape that is
// not ideally specular, or a causticEmitter flag on an environment or directional emitter, is an error.
#pragma once
#include "integrators/caustic_connection.h"
#include "manifold/sms.h"

namespace pf {

class Properties;
class Shape;

class SmsConnection final : public CausticConnection {
public:
    explicit SmsConnection(const Properties &props);
    void check(const Scene &scene) const override;
    void begin() const override;
    void end() const override;
    bool receives(const Intersection &its) const override;
    int chainLength() const override { return bounces_; }
    Spectrum estimate(const Scene &scene, Sampler &sampler, const Intersection &its, int budget) const override;
    bool casts(const Intersection &its, uint32_t sampledLobe) const override;
    bool connectsTo(const Emitter &emitter) const override;

    const SmsSettings &settings() const { return settings_; }
    const SmsStatistics &statistics() const { return stats_; }

private:
    SmsSettings settings_;
    int bounces_ = 1;
    mutable SmsStatistics stats_;
};

}  // namespace pf
