#include "core/sobol_matrices.h"

#include <array>
#include <boost/random/detail/sobol_table.hpp>
#include <vector>

#include "core/owen_sobol.h"

namespace pf::sobol {

namespace {

using JoeKuo = boost::random::detail::qrng_tables::sobol;
static_assert(JoeKuo::max_dimension >= kMatrixDimensions, "Boost's table holds fewer dimensions than asked");

// Direction numbers m_1..m_32 of dimension d >= 1 (odd integers, m_j < 2^j), from its primitive polynomial
// x^s + a_1 x^(s-1) + ... + a_(s-1) x + 1 and initial values m_1..m_s:
//   m_j = 2 a_1 m_(j-1) ^ 4 a_2 m_(j-2) ^ ... ^ 2^(s-1) a_(s-1) m_(j-s+1) ^ 2^s m_(j-s) ^ m_(j-s).
std::array<uint32_t, 32> directionNumbers(int d) {
    const uint32_t poly = JoeKuo::polynomial(static_cast<size_t>(d - 1));
    const int s = 31 - __builtin_clz(poly);
    std::array<uint32_t, 32> m{};
    for (int j = 0; j < 32; ++j) {
        if (j < s) {
            m[j] = JoeKuo::minit(static_cast<size_t>(d - 1), static_cast<size_t>(j));
            continue;
        }
        uint32_t v = m[j - s] ^ (m[j - s] << s);
        for (int k = 1; k < s; ++k)  // a_k is the coefficient of x^(s-k): bit s-k of the polynomial
            if ((poly >> (s - k)) & 1u) v ^= m[j - k] << k;
        m[j] = v;
    }
    return m;
}

std::vector<uint32_t> buildColumns() {
    std::vector<uint32_t> columns(static_cast<size_t>(kMatrixDimensions) * 32);
    for (int d = 0; d < kMatrixDimensions; ++d) {
        const std::array<uint32_t, 32> m = d == 0 ? std::array<uint32_t, 32>{} : directionNumbers(d);
        for (int b = 0; b < 32; ++b) {
            // Column b is m_(b+1) / 2^(b+1) as a 32-bit fraction; van der Corput's m_j are all 1.
            const uint32_t column = (d == 0 ? 1u : m[b]) << (31 - b);
            columns[static_cast<size_t>(d) * 32 + b] = reverseBits(column);
        }
    }
    return columns;
}

std::vector<uint32_t> buildDigitTables() {
    std::vector<uint32_t> tables(static_cast<size_t>(kMatrixDimensions) * 128);
    for (int d = 0; d < kMatrixDimensions; ++d)
        for (uint32_t p = 0; p < 8; ++p)
            for (uint32_t v = 0; v < 16; ++v)
                tables[static_cast<size_t>(d) * 128 + p * 16 + v] = reversedPoint(reversedColumns(d), v << (4 * p));
    return tables;
}

}  // namespace

const uint32_t *reversedColumns(int d) {
    static const std::vector<uint32_t> columns = buildColumns();
    return columns.data() + static_cast<size_t>(d) * 32;
}

const uint32_t *reversedDigitTables(int d) {
    static const std::vector<uint32_t> tables = buildDigitTables();
    return tables.data() + static_cast<size_t>(d) * 128;
}

}  // namespace pf::sobol
