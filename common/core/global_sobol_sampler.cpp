#include "core/global_sobol_sampler.h"

#include <algorithm>
#include <stdexcept>

#include "core/owen_sobol.h"
#include "core/sobol_matrices.h"

namespace pf {

namespace {

constexpr uint64_t kMask48 = (uint64_t(1) << 48) - 1;

// The second dimension's k-bit prefix (its top k bits) at an index.
uint32_t secondPrefix(uint32_t index, int k) { return k == 0 ? 0 : sobol::secondDimension(index) >> (32 - k); }

}  // namespace

GlobalSobolSampler::GlobalSobolSampler(int filmWidth, int filmHeight)
    : width_(filmWidth),
      log2Side_(0),
      widthReciprocal_(((uint64_t(1) << 47) + static_cast<uint64_t>(filmWidth) - 1) / static_cast<uint64_t>(filmWidth)),
      tables_(sobol::reversedDigitTables(0)) {
    const int side = std::max(filmWidth, filmHeight);
    if (filmWidth < 1 || filmHeight < 1 || side > kMaxSide)
        throw std::invalid_argument("the global Sobol sampler needs a film of 1 to " + std::to_string(kMaxSide) +
                                    " pixels a side");
    while ((1 << log2Side_) < side) ++log2Side_;
    // The row prefix depends linearly (over GF(2)) on index bits k..2k-1 through a k x k matrix A, whose column j
    // is the prefix of bit k+j; it is invertible because the first 2^(2k) points form a (0,2k,2)-net. Gauss-Jordan
    // elimination on [A | I], kept as row bit masks, leaves A^-1; its columns are stored.
    const int k = log2Side_;
    std::array<uint32_t, 16> rows{}, inverse{};
    for (int j = 0; j < k; ++j) {
        const uint32_t column = secondPrefix(1u << (k + j), k);
        for (int r = 0; r < k; ++r)
            if ((column >> r) & 1u) rows[r] |= 1u << j;
    }
    for (int r = 0; r < k; ++r) inverse[r] = 1u << r;
    for (int c = 0; c < k; ++c) {
        int pivot = c;
        while (pivot < k && !((rows[pivot] >> c) & 1u)) ++pivot;
        if (pivot == k) throw std::logic_error("the Sobol film dimensions are not a (0,2)-sequence");
        std::swap(rows[c], rows[pivot]);
        std::swap(inverse[c], inverse[pivot]);
        for (int r = 0; r < k; ++r)
            if (r != c && ((rows[r] >> c) & 1u)) rows[r] ^= rows[c], inverse[r] ^= inverse[c];
    }
    // inverse[r] is row r of A^-1: bit t set where target bit t contributes to solution bit r. Transposed into
    // columns, u = xor of rowInverse_[t] over the target's set bits.
    for (int r = 0; r < k; ++r)
        for (int t = 0; t < k; ++t)
            if ((inverse[r] >> t) & 1u) rowInverse_[t] |= 1u << r;
}

GlobalSobolSampler::DimensionSeeds GlobalSobolSampler::seeds(uint32_t dimension) const {
    const uint64_t a = mix64(renderSeed_ ^ (static_cast<uint64_t>(dimension) << 1 | 1));
    return {static_cast<uint32_t>(a), (a >> 32) & 0xffffu};
}

void GlobalSobolSampler::start(uint64_t seed, uint64_t pixelIndex, uint64_t sampleIndex) {
    const int k = log2Side_;
    const int passBits = 32 - 2 * k;
    const uint64_t epoch = sampleIndex >> passBits;
    if (!seedKnown_ || seed != seed_ || epoch != epoch_) {
        seed_ = seed, epoch_ = epoch, seedKnown_ = true;
        renderSeed_ = hashCombine(hashCombine(seed, 0x47534f42u /* "GSOB" */), epoch);
        const uint64_t a = mix64(renderSeed_), b = mix64(a);
        shiftX_ = static_cast<uint32_t>(a), shiftY_ = static_cast<uint32_t>(a >> 32);
        lowX_ = b & kMask48, lowY_ = mix64(b) & kMask48;
        for (uint32_t d = 0; d < kTabulated; ++d) table_[d] = seeds(d + 2);
    }
    dimension_ = 0;
    independent_.reset(seed, pixelIndex, sampleIndex);

    // The grid cell that the digital shift moves onto this pixel, and the index of block `pass` that lands there.
    // Division by the width as a multiplication by its reciprocal rounded up (exact for pixelIndex * width < 2^47,
    // Granlund and Montgomery 1994, §4).
    const uint32_t y = static_cast<uint32_t>((pixelIndex * widthReciprocal_) >> 47);
    const uint32_t x = static_cast<uint32_t>(pixelIndex - static_cast<uint64_t>(y) * static_cast<uint64_t>(width_));
    const uint32_t pass = static_cast<uint32_t>(sampleIndex & ((uint64_t(1) << passBits) - 1));
    uint32_t index = pass << (2 * k);
    if (k > 0) {
        const uint32_t column = x ^ (shiftX_ >> (32 - k)), row = y ^ (shiftY_ >> (32 - k));
        index |= sobol::reverseBits(column) >> (32 - k);  // van der Corput: index bit j is the column's bit k-1-j
        // (A pixel index past the film would put bits above k into the row; they are dropped.)
        uint32_t target = (row ^ secondPrefix(index, k)) & ((1u << k) - 1), u = 0;
        for (; target != 0; target &= target - 1) u ^= rowInverse_[__builtin_ctz(target)];
        index |= u << k;
    }
    index_ = index;
    // Within the pixel: the fraction's bits below the grid's k, then random bits down to 2^-48.
    const uint64_t fx = sobol::reverseBits(index) ^ shiftX_, fy = sobol::secondDimension(index) ^ shiftY_;
    const uint64_t lowMask = (uint64_t(1) << (16 + k)) - 1;
    ahead_ = {static_cast<double>(static_cast<int64_t>(((fx << (16 + k)) & kMask48) | (lowX_ & lowMask))) * 0x1.0p-48,
              static_cast<double>(static_cast<int64_t>(((fy << (16 + k)) & kMask48) | (lowY_ & lowMask))) * 0x1.0p-48};
}

double GlobalSobolSampler::number(uint32_t d) {
    if (d >= static_cast<uint32_t>(sobol::kMatrixDimensions)) return independent_.get().next1D();
    const DimensionSeeds s = d - 2 < kTabulated ? table_[d - 2] : seeds(d);
    const uint32_t reversed = sobol::reversedPointByDigits(tables_ + 128 * d, index_);
    return sobol::toUnit(sobol::reverseBits(sobol::laineKarras(reversed, s.scramble)), s.lowBits);
}

Vec2 GlobalSobolSampler::pair(uint32_t d) {
    if (d + 1 >= static_cast<uint32_t>(sobol::kMatrixDimensions)) {
        const double a = number(d);
        return {a, number(d + 1)};
    }
    // Both fractions turned back by one 64-bit reversal.
    const uint32_t rx = sobol::reversedPointByDigits(tables_ + 128 * d, index_);
    const uint32_t ry = sobol::reversedPointByDigits(tables_ + 128 * (d + 1), index_);
    const DimensionSeeds sx = d - 2 < kTabulated ? table_[d - 2] : seeds(d);
    const DimensionSeeds sy = d - 1 < kTabulated ? table_[d - 1] : seeds(d + 1);
    const uint64_t xy = sobol::reverseBits64((static_cast<uint64_t>(sobol::laineKarras(ry, sy.scramble)) << 32) |
                                             sobol::laineKarras(rx, sx.scramble));
    return {sobol::toUnit(static_cast<uint32_t>(xy >> 32), sx.lowBits),
            sobol::toUnit(static_cast<uint32_t>(xy), sy.lowBits)};
}

void GlobalSobolSampler::startPart(uint32_t part) {
    const uint32_t base = part * kDimensionsPerPart;
    if (dimension_ >= base) return;
    dimension_ = base;
    ahead_ = pair(base);
}

double GlobalSobolSampler::next1D() {
    // ahead_ holds dimensions d and d + 1: the first is this request's, the second stays ahead with d + 2 beside it.
    const uint32_t d = dimension_++;
    const double u = ahead_.x;
    ahead_ = {ahead_.y, number(d + 2)};
    return u;
}

Vec2 GlobalSobolSampler::next2D() {
    const uint32_t d = dimension_;
    dimension_ += 2;
    const Vec2 p = ahead_;
    ahead_ = pair(d + 2);
    return p;
}

}  // namespace pf
