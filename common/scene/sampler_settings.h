// The scene's <sampler>: its sample count, and which numbers the pixel samples of image tasks draw.
// `independent` draws per-pixel PCG32 streams (core/rng.h); Mitsuba 0.6's low-discrepancy samplers
// (stratified, ldsampler, halton, hammersley, sobol) all draw one progressive Owen-scrambled Sobol
// sequence (core/ld_sampler.h, which says how that differs from Mitsuba's point sets), or, for `sobol` with
// layout "image", Mitsuba's global Sobol sequence (core/global_sobol_sampler.h). Markov-chain
// integrators and their seeding draw independent numbers whatever the scene asks.
#pragma once
#include <cstdint>

#include "core/sample_sequence.h"
#include "scene/object.h"

namespace pf {

class SamplerSettings : public Object {
public:
    SamplerSettings(int sampleCount, SampleSequence sequence) : sampleCount_(sampleCount), sequence_(sequence) {}
    // Samples per pixel, after the rounding the Mitsuba sampler of that name applies.
    int sampleCount() const { return sampleCount_; }
    const SampleSequence &sequence() const { return sequence_; }

private:
    int sampleCount_;
    SampleSequence sequence_;
};

}  // namespace pf
