// Low-discrepancy pixel samples: the scene's `stratified`, `ldsampler`, `halton`, `hammersley` and
// `sobol` samplers. Every 1D and 2D request of a pixel sample is its own padded dimension (Kollig and
// Keller 2002, §3; pbrt-v3 §7.4's "padding"): request d of sample i takes point i' of an Owen-scrambled
// Sobol (0,2)-sequence (first dimension alone for 1D requests), where i' is i shuffled by a nested
// uniform scramble and both the shuffle and the scramble are seeded by a hash of (seed, d) xor a hash of
// (seed, pixel) (Burley 2020, §4-5; core/owen_sobol.h). So the first 2^m samples of every pixel are a (0,m,2)-net in
// each 2D request and stratified in each 1D request, for every m, and progressively: a time-budgeted render stopped
// after any count keeps the stratification of its largest power of two. Each single number is still
// uniform on [0,1), so every estimator stays unbiased; successive samples of a pixel are not independent
// (negatively correlated by design), which only tests that estimate variance per sample must know. An
// integrator whose later requests would otherwise move with an earlier part's length starts them as a new
// part (Sampler::startPart; BDPT's emitter walk and direct samples), at a fixed request.
//
// Differences from Mitsuba 0.6, whose samplers draw other point sets: pathfarm's sample counts are not
// known when a timed render starts, and farm tasks split a pixel's samples into ranges, so all five
// samplers take this one progressive sequence. As in Mitsuba's `stratified` and `ldsampler`, their
// `dimension` parameter bounds the 1D and the 2D requests that get stratified numbers; later requests
// draw independent ones. Mitsuba's `halton`, `hammersley` and `sobol` stratify every request.
#pragma once
#include <array>
#include <cstdint>
#include <memory>

#include "core/sample_sequence.h"
#include "core/sampler.h"

namespace pf {

class LowDiscrepancySampler final : public PixelSampler {
public:
    explicit LowDiscrepancySampler(int dimension = 0) : dimension_(dimension) {}
    void start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) override;
    double next1D() override;
    Vec2 next2D() override;
    // Part p starts at request p * kRequestsPerPart of each kind.
    void startPart(uint32_t part) override;
    static constexpr uint32_t kRequestsPerPart = 64;

private:
    // The hash seeds of one request: the index shuffle, the scrambles of its coordinates and the bits below
    // their 32-bit fractions.
    struct RequestSeeds {
        uint32_t shuffle, scrambleX, scrambleY;
        uint64_t lowBitsX, lowBitsY;
    };
    // The render's seeds of request `request` of kind `kind` (1 or 2 dimensions).
    RequestSeeds seeds(uint64_t kind, uint32_t request) const;
    // The seeds of that request in this pixel: the render's, xor the pixel's mask.
    RequestSeeds pixelSeeds(uint64_t kind, uint32_t request) const;
    // The numbers of request `request` of each kind in this sample.
    double point1D(uint32_t request) const;
    Vec2 point2D(uint32_t request) const;
    bool stratified(uint32_t request) const { return dimension_ == 0 || request < static_cast<uint32_t>(dimension_); }

    // The render's seeds of the requests of each kind in BDPT's three parts (requests 0 .. 191), computed when the
    // seed changes: a request costs a lookup instead of two hashes.
    static constexpr uint32_t kTabulated = 3 * kRequestsPerPart;
    int dimension_;
    uint64_t seed_ = 0, pixel_ = 0, renderSeed_ = 0;
    bool seedKnown_ = false, pixelKnown_ = false;
    std::array<RequestSeeds, kTabulated> table1D_{}, table2D_{};
    RequestSeeds pixelMask_{};
    uint32_t reversedIndex_ = 0;
    uint32_t requests1D_ = 0, requests2D_ = 0;
    // The numbers of requests requests1D_ and requests2D_, computed ahead when those requests are stratified.
    double ahead1D_ = 0;
    Vec2 ahead2D_;
    // Requests past `dimension` draw from an independent stream.
    DeferredIndependentSampler independent_;
};

// A pixel sampler of the given sequence for a film of that size: the independent one, the padded low-discrepancy
// one, or the global Sobol sequence (core/global_sobol_sampler.h).
std::unique_ptr<PixelSampler> makePixelSampler(const SampleSequence &sequence, int filmWidth, int filmHeight);

}  // namespace pf
