#include "core/ld_sampler.h"

#include <algorithm>

#include "core/global_sobol_sampler.h"
#include "core/owen_sobol.h"

namespace pf {

void LowDiscrepancySampler::start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) {
    // A request's seeds are the render's seeds of that request, xor one mask per pixel: every pixel's seeds are
    // uniformly distributed (so is each of its numbers), and a sample costs a table lookup per request and a
    // hash per pixel, which matters under `--time`, where each pass draws one sample of every pixel.
    if (!seedKnown_ || seed != seed_) {
        seed_ = seed, seedKnown_ = true, pixelKnown_ = false;
        renderSeed_ = hashCombine(seed, 0x4c44u /* "LD" */);
        for (uint32_t r = 0; r < kTabulated; ++r) table1D_[r] = seeds(1, r), table2D_[r] = seeds(2, r);
    }
    if (!pixelKnown_ || pixelIndex != pixel_) {
        pixel_ = pixelIndex, pixelKnown_ = true;
        const uint64_t a = hashCombine(renderSeed_, pixelIndex), b = mix64(a);
        pixelMask_ = {static_cast<uint32_t>(a), static_cast<uint32_t>(a >> 32), static_cast<uint32_t>(b),
                      (b >> 32) & 0xffffu, b >> 48};
    }
    // A pixel's sample counts stay far below 2^32 (scene/sampler_settings.cpp bounds them at 2^24 per
    // render); indices are taken modulo 2^32, which only repeats a pixel's points past that.
    reversedIndex_ = sobol::reverseBits(static_cast<uint32_t>(sampleIndex));
    requests1D_ = requests2D_ = 0;
    independent_.reset(seed, pixelIndex, sampleIndex);
    if (stratified(0)) ahead1D_ = point1D(0), ahead2D_ = point2D(0);
}

LowDiscrepancySampler::RequestSeeds LowDiscrepancySampler::seeds(uint64_t kind, uint32_t request) const {
    const uint64_t a = mix64(renderSeed_ ^ ((kind << 32) | request)), b = mix64(a);
    // The 16 bits below a 32-bit fraction are one uniform offset per pixel and request: each number stays
    // uniform on [0,1) (to 2^-48), as an Owen scramble of unlimited depth would leave it.
    return {static_cast<uint32_t>(a), static_cast<uint32_t>(a >> 32), static_cast<uint32_t>(b), (b >> 32) & 0xffffu,
            b >> 48};
}

inline LowDiscrepancySampler::RequestSeeds LowDiscrepancySampler::pixelSeeds(uint64_t kind, uint32_t request) const {
    const RequestSeeds s = request < kTabulated ? (kind == 1 ? table1D_ : table2D_)[request] : seeds(kind, request);
    return {s.shuffle ^ pixelMask_.shuffle, s.scrambleX ^ pixelMask_.scrambleX, s.scrambleY ^ pixelMask_.scrambleY,
            s.lowBitsX ^ pixelMask_.lowBitsX, s.lowBitsY ^ pixelMask_.lowBitsY};
}

void LowDiscrepancySampler::startPart(uint32_t part) {
    const uint32_t base = part * kRequestsPerPart;
    if (requests1D_ < base) {
        requests1D_ = base;
        if (stratified(base)) ahead1D_ = point1D(base);
    }
    if (requests2D_ < base) {
        requests2D_ = base;
        if (stratified(base)) ahead2D_ = point2D(base);
    }
}

double LowDiscrepancySampler::next1D() {
    const uint32_t request = requests1D_++;
    if (!stratified(request)) return independent_.get().next1D();
    // Computed ahead, as next2D's points are.
    const double u = ahead1D_;
    if (stratified(request + 1)) ahead1D_ = point1D(request + 1);
    return u;
}

double LowDiscrepancySampler::point1D(uint32_t request) const {
    // The shuffled index's first coordinate is reverseBits(index); its Owen scramble reverses it back first.
    const RequestSeeds s = pixelSeeds(1, request);
    const uint32_t index = sobol::shuffledIndex(reversedIndex_, s.shuffle);
    return sobol::toUnit(sobol::reverseBits(sobol::laineKarras(index, s.scrambleX)), s.lowBitsX);
}

Vec2 LowDiscrepancySampler::next2D() {
    const uint32_t request = requests2D_++;
    if (!stratified(request)) return independent_.get().next2D();
    // The point was computed ahead, at the previous request (or at start): its hash chains (about 70 cycles of
    // dependent multiplies, shifts and loads) run while the caller works, not while it waits for the result. The
    // price is one point per sample computed and never used.
    const Vec2 p = ahead2D_;
    if (stratified(request + 1)) ahead2D_ = point2D(request + 1);
    return p;
}

Vec2 LowDiscrepancySampler::point2D(uint32_t request) const {
    // One shuffle for both coordinates keeps the pair a (0,2)-sequence; each coordinate has its own scramble.
    // Both scrambles take their coordinate bit-reversed: the first coordinate's reversal is the shuffled index
    // itself, the second's comes from its table; one 64-bit reversal then turns both back (x in the high half).
    const RequestSeeds s = pixelSeeds(2, request);
    const uint32_t index = sobol::shuffledIndex(reversedIndex_, s.shuffle);
    const uint64_t xy = sobol::reverseBits64(
        (static_cast<uint64_t>(sobol::laineKarras(sobol::reversedSecondDimension(index), s.scrambleY)) << 32) |
        sobol::laineKarras(index, s.scrambleX));
    return {sobol::toUnit(static_cast<uint32_t>(xy >> 32), s.lowBitsX),
            sobol::toUnit(static_cast<uint32_t>(xy), s.lowBitsY)};
}

std::unique_ptr<PixelSampler> makePixelSampler(const SampleSequence &sequence, int filmWidth, int filmHeight) {
    // Films beyond the global sequence's grid (2^15 pixels a side) take the padded one.
    if (sequence.acrossPixels && std::max(filmWidth, filmHeight) <= GlobalSobolSampler::kMaxSide)
        return std::make_unique<GlobalSobolSampler>(filmWidth, filmHeight);
    if (sequence.lowDiscrepancy) return std::make_unique<LowDiscrepancySampler>(sequence.dimension);
    return std::make_unique<IndependentSampler>();
}

}  // namespace pf
