// The luminance pilot of burst rendering (ERPT, MEPT; ALGORITHMS.md §5.3): Mitsuba's `luminanceSamples`
// pass, a small BDPT run of its own that estimates W, the mean pixel luminance of the image the chains
// render, before any burst starts. Bursts then deposit equal quanta W / (numChains · chainLength).
//
// Why a pass of its own: a seed of weight w launches nu = numChains · w / W chains on average (stochastically
// rounded), each of weight w / nu, so its bursts carry w in expectation for ANY W > 0 that does not depend
// on the seed (E[floor(nu + U)] · w / nu = w). W taken from the seeds themselves (the earlier design: the
// whole image's seeding pool) would need every seed of the image before the first burst, i.e. a global
// pool; a pilot in its own random stream needs nothing but its own samples, so bursts can run block by
// block and pass by pass (render/burst.h) with memory bounded by the blocks in flight.
//
// The pilot takes `samples` BDPT samples, sample j in a pixel drawn uniformly from the j-th of `samples`
// equal strata of the crop window's pixels (stratified, so few samples still cover the image), with the
// render loop's sampler seeded by (pilot seed, pixel, j), so that its paths regenerate from PathRecords with
// the pilot seed (BDPT::regenerate). The sum of every strategy's luminance of a sample, light tracing
// included, times pixels / samples, is an unbiased estimate of the image's total luminance b̂.
#pragma once
#include <cstdint>

#include "render/seeding.h"

namespace pf {

// The pilot's seed: a stream apart from the seeds', the chains' and the direct component's.
uint64_t pilotSeed(uint64_t jobSeed);

// depthLuminance holds b̂ per path depth (paths shorter than config.minDepth left out, as in seeding),
// samples the BDPT samples taken; candidates the pilot's paths with their share of b̂ when `keep` (records
// that regenerate with pilotSeed(jobSeed), for tuning the chains on them: integrators/erpt.h), else none.
SeedingResult runPilot(const Scene &scene, const SeedingConfig &config, uint64_t jobSeed, uint64_t samples,
                       bool keep = false);

}  // namespace pf
