// The directional emitter built from code rather than from a scene file: the sun of `sun` and `sunsky`
// with sunRadiusScale = 0, as in Mitsuba 0.6.
#pragma once
#include <memory>

#include "emitter/emitter.h"

namespace pf {

// Parallel light travelling along `direction` (world space, any length > 0) with the given irradiance.
std::shared_ptr<Emitter> makeDirectionalEmitter(const Vec3 &direction, const Spectrum &irradiance,
                                                double samplingWeight);

}  // namespace pf
