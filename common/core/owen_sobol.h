// Owen-scrambled Sobol points in base 2, computed for any index from a hash (no stored permutations):
// Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020, §3-4, building on Laine and
// Karras's observation that a multiply-xor hash whose output bit b depends only on input bits 0..b is
// a nested uniform (Owen) scramble once applied to the bit-reversed value.
//
// The first two Sobol dimensions form a (0,2)-sequence (Sobol 1967; Niederreiter 1992, §4.5): every
// aligned block of 2^m consecutive indices is a (0,m,2)-net, i.e. each elementary interval of area 2^-m
// holds exactly one point. Owen scrambling keeps that property and makes every single point uniformly
// distributed over the unit square (Owen 1995), which is what keeps estimators built on it unbiased.
#pragma once
#include <array>
#include <cstdint>

namespace pf::sobol {

constexpr uint32_t reverseBits(uint32_t x) {
    x = __builtin_bswap32(x);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    return ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
}

// A permutation of 32-bit words in which output bit b depends only on input bits 0..b (additions and
// multiplications carry upwards only); the constants are Burley's (2020, listing 2).
constexpr uint32_t laineKarras(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Owen scrambling of a 32-bit binary fraction (most significant bit first): each bit is flipped by a
// hash of the bits above it.
constexpr uint32_t nestedUniformScramble(uint32_t x, uint32_t seed) {
    return reverseBits(laineKarras(reverseBits(x), seed));
}

namespace detail {
// The second Sobol dimension's generator matrix applied to one byte of the index at byte position
// `shift` / 8: direction numbers v_1 = 2^31, v_k = v_{k-1} xor (v_{k-1} >> 1) (the Pascal matrix mod 2). With
// `reversed`, each image bit-reversed (reversal commutes with xor, so the lookups combine the same way).
constexpr std::array<uint32_t, 256> secondDimensionTable(int shift, bool reversed) {
    std::array<uint32_t, 256> table{};
    for (uint32_t byte = 0; byte < 256; ++byte) {
        uint32_t v = 1u << 31, r = 0;
        for (int bit = 0; bit < shift + 8; ++bit, v ^= v >> 1)
            if (bit >= shift && ((byte >> (bit - shift)) & 1u)) r ^= v;
        table[byte] = reversed ? reverseBits(r) : r;
    }
    return table;
}
template <bool Reversed>
inline constexpr std::array<std::array<uint32_t, 256>, 4> kSecondDimension = {
    secondDimensionTable(0, Reversed), secondDimensionTable(8, Reversed), secondDimensionTable(16, Reversed),
    secondDimensionTable(24, Reversed)};
template <bool Reversed>
constexpr uint32_t secondDimension(uint32_t index) {
    const auto &t = kSecondDimension<Reversed>;
    return t[0][index & 0xffu] ^ t[1][(index >> 8) & 0xffu] ^ t[2][(index >> 16) & 0xffu] ^ t[3][index >> 24];
}
}  // namespace detail

// The index-th point of the first Sobol dimension (van der Corput's radical inverse) as a 32-bit fraction.
constexpr uint32_t firstDimension(uint32_t index) { return reverseBits(index); }

// The index-th point of the second Sobol dimension: the matrix is linear over GF(2), so the index's bytes
// are looked up separately and their images combined by xor.
constexpr uint32_t secondDimension(uint32_t index) { return detail::secondDimension<false>(index); }

// The index-th point of the second Sobol dimension, bit-reversed (ready for laineKarras: its Owen scramble is
// reverseBits(laineKarras(reversedSecondDimension(index), seed))).
constexpr uint32_t reversedSecondDimension(uint32_t index) { return detail::secondDimension<true>(index); }

// Shuffled indices without reversing the index for every dimension (Burley 2020, §4-5): the shuffle
// nestedUniformScramble(i, shuffle) is reverseBits(laineKarras(reverseBits(i), shuffle)), and a sample reverses
// its index once for all of its requests.
constexpr uint32_t shuffledIndex(uint32_t reversedIndex, uint32_t shuffle) {
    return reverseBits(laineKarras(reversedIndex, shuffle));
}

// Both 32-bit halves reversed and swapped: reverseBits of each half in one pass, for a 2D point's two
// coordinates at once.
constexpr uint64_t reverseBits64(uint64_t x) {
    x = __builtin_bswap64(x);
    x = ((x & 0x0f0f0f0f0f0f0f0full) << 4) | ((x & 0xf0f0f0f0f0f0f0f0ull) >> 4);
    x = ((x & 0x3333333333333333ull) << 2) | ((x & 0xccccccccccccccccull) >> 2);
    return ((x & 0x5555555555555555ull) << 1) | ((x & 0xaaaaaaaaaaaaaaaaull) >> 1);
}

// A 32-bit binary fraction with 16 more bits below it (`lowBits` < 2^16), as a double in [0, 1). The value is below
// 2^48, so the signed conversion (one instruction, unlike the unsigned one) is exact.
inline double toUnit(uint32_t fraction, uint64_t lowBits) {
    return static_cast<double>(static_cast<int64_t>((static_cast<uint64_t>(fraction) << 16) | lowBits)) * 0x1.0p-48;
}

}  // namespace pf::sobol
