// Samplers hand out the uniform numbers an integrator consumes. Integrators take the abstract Sampler,
// so the same BDPT code runs on independent streams (path tracing, seeding) and on the mutated
// primary-sample vectors of PSSMLT/MMLT (Kelemen et al. 2002), which replay and perturb a recorded
// sequence.
#pragma once
#include "core/rng.h"
#include "core/vector.h"

namespace pf {

class Sampler {
public:
    virtual ~Sampler() = default;
    virtual double next1D() = 0;
    // Where the numbers of part `part` of a sample begin (BDPT: 0 the camera walk, 1 the emitter walk, 2 the
    // direct-sampling numbers). A low-discrepancy sampler starts part p at a fixed request, or right after the
    // requests made so far where they reach past it, so that a part's k-th request takes the same stratified
    // dimension in every sample whatever the parts before it consumed (Mitsuba's BDPT alternates its two walks
    // for the same reason). Requests only move forward, so no number of a sample is drawn twice. Samplers whose
    // numbers have no such places (independent streams, Markov chains' primary samples) continue in order.
    virtual void startPart(uint32_t part) { (void)part; }
    // Two numbers used together as one point of the unit square (a pixel position, a direction):
    // low-discrepancy samplers stratify them jointly.
    virtual Vec2 next2D() {
        const double a = next1D();
        return {a, next1D()};
    }
};

// The numbers of one pixel sample, a pure function of (seed, pixel index, sample index): the same
// triple always yields the same stream, which is what makes renders reproducible across thread counts
// and farm tasks.
class PixelSampler : public Sampler {
public:
    virtual void start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) = 0;
};

// Independent uniform numbers from a PCG32 stream per pixel sample. Seeding draws from it, so that a
// worker regenerates a BDPT candidate path exactly (ALGORITHMS.md §2.4-2.5).
class IndependentSampler final : public PixelSampler {
public:
    IndependentSampler() = default;
    IndependentSampler(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) {
        start(seed, pixelIndex, sampleIndex);
    }
    void start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) override {
        rng_.seed(hashCombine(hashCombine(seed, pixelIndex), sampleIndex), mix64(seed) ^ pixelIndex);
    }
    double next1D() override { return rng_.nextDouble(); }

private:
    PCG32 rng_;
};

// The independent stream of one pixel sample, started on first use: low-discrepancy samplers draw from it past
// the requests they stratify, which most samples never reach.
class DeferredIndependentSampler {
public:
    void reset(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) {
        seed_ = seed, pixel_ = pixelIndex, sample_ = sampleIndex, started_ = false;
    }
    IndependentSampler &get() {
        if (!started_) {
            stream_.start(seed_, pixel_, sample_);
            started_ = true;
        }
        return stream_;
    }

private:
    uint64_t seed_ = 0, pixel_ = 0, sample_ = 0;
    bool started_ = false;
    IndependentSampler stream_;
};

}  // namespace pf
