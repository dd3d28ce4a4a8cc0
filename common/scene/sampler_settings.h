// The scene's <sampler>: only its sample count matters to pathfarm. Mitsuba 0.6 offers several
// low-discrepancy samplers (stratified, ldsampler, halton, hammersley, sobol); pathfarm accepts all of
// them with their parameters so that Mitsuba scenes load unchanged, but always draws independent
// uniform numbers from per-pixel PCG32 streams (core/rng.h). Independent samples keep every estimator
// unbiased with simple, reproducible seeding across farm tasks, and are what MLT-type chains need
// anyway; the price is somewhat higher variance at low sample counts than a QMC sampler would give.
#pragma once
#include <cstdint>

#include "scene/object.h"

namespace pf {

class SamplerSettings : public Object {
public:
    explicit SamplerSettings(int sampleCount) : sampleCount_(sampleCount) {}
    // Samples per pixel, after the rounding the Mitsuba sampler of that name applies.
    int sampleCount() const { return sampleCount_; }

private:
    int sampleCount_;
};

}  // namespace pf
