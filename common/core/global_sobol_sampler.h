// The scene's `sobol` sampler with layout "image": every number of a pixel sample comes from one index of one
// multi-dimensional Sobol sequence that runs through the whole image, as in Mitsuba 0.6's `sobol` and
// pbrt-v3's SobolSampler (pbrt-v3 §7.7). Its first two dimensions are the film position: the film is covered
// by a square grid of 2^k x 2^k pixels, and since those two dimensions form a (0,2)-sequence, each block of 4^k
// consecutive indices puts exactly one point into every pixel of the grid. Sample i of a pixel is the point of
// block i that falls into it; its index is found by inverting the two dimensions' matrices on the index's low
// 2k bits (Grünschloß and Keller 2012, "Enumerating quasi-Monte Carlo point sequences in elementary intervals").
//
// So the image's samples are stratified together, not pixel by pixel: sample i of all pixels is one net in
// every pair of dimensions (up to the pair's t), the points of neighbouring pixels are stratified jointly with
// their film positions, and samples 0..n-1 of the image are the sequence's first n blocks, progressively, for
// a render stopped under `--time` after any pass. That is what a reconstruction filter wider than a pixel and
// any average over a region of the image profit from. The padded sampler (core/ld_sampler.h, the default)
// stratifies each pixel's own samples better in later dimensions (their t-values jointly with the film
// dimensions are not 0) but leaves pixels independent; README, "Samplers", has the figures of both.
//
// Randomization (each sample's numbers jointly uniform, so every estimator stays unbiased): the film dimensions
// take a random digital shift (which moves the grid's pixels among themselves and each point uniformly within
// its pixel), every later dimension its own Owen scramble (Burley 2020's hash, core/owen_sobol.h), and every
// number 16 random bits below its 32. Requests take dimensions in the order they are made (a 2D request two of
// them), a new part of the sample (Sampler::startPart) from a fixed dimension on; past kMatrixDimensions they
// draw from the sample's independent stream. Indices are 32-bit: once a
// pixel's samples pass 2^(32-2k), the sequence starts again under new random shifts and scrambles (an epoch),
// which keeps each epoch a randomized Sobol sequence of its own.
#pragma once
#include <array>
#include <cstdint>

#include "core/sampler.h"

namespace pf {

class GlobalSobolSampler final : public PixelSampler {
public:
    // The grid's side is the smallest power of two at least max(width, height), up to kMaxSide.
    static constexpr int kMaxSide = 1 << 15;
    GlobalSobolSampler(int filmWidth, int filmHeight);
    // pixelIndex = y * filmWidth + x, over the whole film (crop windows included).
    void start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) override;
    double next1D() override;
    Vec2 next2D() override;
    // Part p starts at dimension p * kDimensionsPerPart (Sampler::startPart).
    void startPart(uint32_t part) override;
    static constexpr uint32_t kDimensionsPerPart = 32;

    // The sequence's index of this sample (for tests): which point of which block it takes.
    uint32_t index() const { return index_; }
    int log2Side() const { return log2Side_; }

private:
    // The random numbers of one dimension: its Owen scramble's seed and the 16 bits below its 32.
    struct DimensionSeeds {
        uint32_t scramble;
        uint64_t lowBits;
    };
    DimensionSeeds seeds(uint32_t dimension) const;
    // The numbers of dimension d, and of dimensions d and d + 1.
    double number(uint32_t d);
    Vec2 pair(uint32_t d);

    // Seeds tabulated for dimensions 2 .. kTabulated + 1: the first dimensions of BDPT's three parts and more.
    static constexpr uint32_t kTabulated = 128;
    int width_, log2Side_;
    // pixelIndex / width_ as a multiplication: (pixelIndex * widthReciprocal_) >> 47 (exact below 2^32 pixels).
    uint64_t widthReciprocal_;
    // Film positions: the index's low k bits are the reversed column; the next k solve for the row through the
    // inverse of the second dimension's matrix on those bits (its columns, one per bit of the row's target).
    std::array<uint32_t, 16> rowInverse_{};
    const uint32_t *tables_;  // sobol::reversedDigitTables(0)
    uint64_t seed_ = 0, epoch_ = 0, renderSeed_ = 0;
    bool seedKnown_ = false;
    uint32_t shiftX_ = 0, shiftY_ = 0;                // digital shifts of the film dimensions
    uint64_t lowX_ = 0, lowY_ = 0;                    // their bits below the sub-pixel fraction
    std::array<DimensionSeeds, kTabulated> table_{};  // dimensions 2 .. kTabulated + 1
    uint32_t index_ = 0, dimension_ = 0;
    // The numbers of dimensions dimension_ and dimension_ + 1, computed ahead: the next request takes one or both,
    // and its bit loop and hashes run while the caller works on the previous numbers.
    Vec2 ahead_;
    DeferredIndependentSampler independent_;  // past kMatrixDimensions
};

}  // namespace pf
