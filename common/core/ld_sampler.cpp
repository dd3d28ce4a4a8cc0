#include "core/ld_sampler.h"

#include "core/owen_sobol.h"

namespace pf {

void LowDiscrepancySampler::start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) {
    // An image task draws all its samples of a pixel in a row: the requests' seeds depend on the pixel
    // only and are kept until it changes.
    if (!pixelKnown_ || seed != seed_ || pixelIndex != pixel_) {
        seed_ = seed, pixel_ = pixelIndex, pixelKnown_ = true;
        pixelSeed_ = hashCombine(hashCombine(seed, pixelIndex), 0x4c44u /* "LD" */);
        known1D_ = known2D_ = 0;
    }
    // A pixel's sample counts stay far below 2^32 (scene/sampler_settings.cpp bounds them at 2^24 per
    // render); indices are taken modulo 2^32, which only repeats a pixel's points past that.
    sample_ = sampleIndex;
    reversedIndex_ = sobol::reverseBits(static_cast<uint32_t>(sampleIndex));
    requests1D_ = requests2D_ = 0;
    independentStarted_ = false;
}

LowDiscrepancySampler::RequestSeeds LowDiscrepancySampler::seeds(uint64_t kind, uint32_t request) const {
    const uint64_t a = mix64(pixelSeed_ ^ ((kind << 32) | request)), b = mix64(a);
    // The 16 bits below a 32-bit fraction are one uniform offset per pixel and request: each number stays
    // uniform on [0,1) (to 2^-48), as an Owen scramble of unlimited depth would leave it.
    return {static_cast<uint32_t>(a), static_cast<uint32_t>(a >> 32), static_cast<uint32_t>(b), (b >> 32) & 0xffffu,
            b >> 48};
}

const LowDiscrepancySampler::RequestSeeds &LowDiscrepancySampler::cached(uint64_t kind, uint32_t request) {
    auto &table = kind == 1 ? seeds1D_ : seeds2D_;
    uint32_t &known = kind == 1 ? known1D_ : known2D_;
    if (request >= table.size()) {
        scratch_ = seeds(kind, request);
        return scratch_;
    }
    for (; known <= request; ++known) table[known] = seeds(kind, known);
    return table[request];
}

IndependentSampler &LowDiscrepancySampler::independent() {
    if (!independentStarted_) {
        independent_.start(seed_, pixel_, sample_);
        independentStarted_ = true;
    }
    return independent_;
}

double LowDiscrepancySampler::toUnit(uint32_t fraction, uint64_t lowBits) {
    // Below 2^48, so the signed conversion (one instruction, unlike the unsigned one) is exact.
    return static_cast<double>(static_cast<int64_t>((static_cast<uint64_t>(fraction) << 16) | lowBits)) * 0x1.0p-48;
}

double LowDiscrepancySampler::next1D() {
    const uint32_t request = requests1D_++;
    if (!stratified(request)) return independent().next1D();
    const RequestSeeds &s = cached(1, request);
    const uint32_t first = sobol::shuffledFirstDimension(reversedIndex_, s.shuffle);
    return toUnit(sobol::nestedUniformScramble(first, s.scrambleX), s.lowBitsX);
}

Vec2 LowDiscrepancySampler::next2D() {
    const uint32_t request = requests2D_++;
    if (!stratified(request)) return independent().next2D();
    // One shuffle for both coordinates keeps the pair a (0,2)-sequence; each coordinate has its own scramble.
    const RequestSeeds &s = cached(2, request);
    const uint32_t first = sobol::shuffledFirstDimension(reversedIndex_, s.shuffle);
    const uint32_t second = sobol::reverseBits(sobol::laineKarras(sobol::secondFromFirstReversed(first), s.scrambleY));
    return {toUnit(sobol::nestedUniformScramble(first, s.scrambleX), s.lowBitsX), toUnit(second, s.lowBitsY)};
}

std::unique_ptr<PixelSampler> makePixelSampler(const SampleSequence &sequence) {
    if (sequence.lowDiscrepancy) return std::make_unique<LowDiscrepancySampler>(sequence.dimension);
    return std::make_unique<IndependentSampler>();
}

}  // namespace pf
