// Independent sampler. A sample is identified by (seed, pixel index, sample index); the same triple
// always yields the same stream, which is what makes renders reproducible across thread counts and
// lets a worker regenerate a BDPT candidate path exactly (issue: Markov-chain tasks).
#pragma once
#include "core/rng.h"
#include "core/vector.h"

namespace pf {

class Sampler {
public:
    Sampler() = default;
    Sampler(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) { start(seed, pixelIndex, sampleIndex); }
    void start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) {
        rng_.seed(hashCombine(hashCombine(seed, pixelIndex), sampleIndex), mix64(seed) ^ pixelIndex);
    }
    double next1D() { return rng_.nextDouble(); }
    Vec2 next2D() {
        const double a = next1D();
        return {a, next1D()};
    }
    PCG32 &rng() { return rng_; }

private:
    PCG32 rng_;
};

}  // namespace pf
