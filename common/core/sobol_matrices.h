// Generator matrices of the Sobol sequence in many dimensions, for samplers that take every number of a
// sample from one index of one multi-dimensional sequence (core/global_sobol_sampler.h).
//
// Dimension d's point at index i is the xor of the columns C_d[b] for the bits b set in i (Sobol 1967;
// Bratley and Fox 1988, §2). The direction numbers are Joe and Kuo's (2008, "Constructing Sobol sequences with
// better two-dimensional projections", the new-joe-kuo-6.21201 set), whose primitive polynomials and initial
// values come from Boost.Random's table (boost/random/detail/sobol_table.hpp); the recurrence that extends them to
// 32 columns is written here (Bratley and Fox 1988, eq. 2).
#pragma once
#include <cstdint>

namespace pf::sobol {

// Dimensions with matrices; a sampler draws later requests from elsewhere.
constexpr int kMatrixDimensions = 1024;

// The 32 columns of dimension d's matrix (d < kMatrixDimensions), each a 32-bit binary fraction bit-reversed (its
// first bit in bit 0), ready for laineKarras (core/owen_sobol.h). Dimension 0 is van der Corput's, dimension 1
// the Pascal matrix of sobol::secondDimension.
const uint32_t *reversedColumns(int d);

// reverseBits of dimension d's point at index i: the xor of reversed columns over the set bits of i.
inline uint32_t reversedPoint(const uint32_t *columns, uint32_t i) {
    uint32_t v = 0;
    for (; i != 0; i &= i - 1) v ^= columns[__builtin_ctz(i)];
    return v;
}

// The same product by lookups: dimension d's 8 x 16 table holds, for each 4-bit digit position p and digit value
// v, the xor of the reversed columns 4p + b over the bits b set in v. Eight loads and no loop whose length
// depends on the index (whose exit a branch predictor misses).
const uint32_t *reversedDigitTables(int d);
inline uint32_t reversedPointByDigits(const uint32_t *tables, uint32_t i) {
    return tables[i & 15u] ^ tables[16 + ((i >> 4) & 15u)] ^ tables[32 + ((i >> 8) & 15u)] ^
           tables[48 + ((i >> 12) & 15u)] ^ tables[64 + ((i >> 16) & 15u)] ^ tables[80 + ((i >> 20) & 15u)] ^
           tables[96 + ((i >> 24) & 15u)] ^ tables[112 + (i >> 28)];
}

}  // namespace pf::sobol
