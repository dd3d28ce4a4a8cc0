#include "emitter/emitter.h"

#include "scene/properties.h"

namespace pf {

// Only area emitters radiate from surfaces and only environment emitters from escaping rays; every
// other emitter is invisible to rays (delta lights cannot be hit).
Spectrum Emitter::eval(const Intersection &, const Vec3 &) const { return Spectrum(0.0); }
Spectrum Emitter::evalEnvironment(const Ray &) const { return Spectrum(0.0); }
bool Emitter::fillDirectSample(DirectSample &, const Ray &) const { return false; }

void Emitter::configureCommon(const Properties &props) {
    samplingWeight_ = props.getFloat("samplingWeight", 1.0);
    // Zero would take the emitter out of light selection while BSDF sampling can still hit it, which
    // leaves the emitter-selection distribution of an all-zero scene undefined.
    if (!(samplingWeight_ > 0)) props.fail("samplingWeight", "must be positive");
    if (props.has("causticEmitter")) causticEmitter_ = props.getBool("causticEmitter");
}

}  // namespace pf
