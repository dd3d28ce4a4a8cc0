// Checks of (0,m,2)-nets and stratified 1D point sets, for the low-discrepancy samplers' tests.
#pragma once
#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "core/vector.h"

namespace pf::test {

// Each of the 2^a x 2^(m-a) elementary intervals of the unit square, for every a, holds exactly one of the 2^m
// points.
inline bool isNet(const std::vector<Vec2> &points, int m) {
    for (int a = 0; a <= m; ++a) {
        std::set<uint64_t> cells;
        for (const Vec2 &p : points)
            cells.insert((static_cast<uint64_t>(p.x * std::ldexp(1.0, a)) << 32) |
                         static_cast<uint64_t>(p.y * std::ldexp(1.0, m - a)));
        if (cells.size() != points.size()) return false;
    }
    return true;
}

// Each of n equal intervals of [0, 1) holds exactly one of the n values.
inline bool isStratified(const std::vector<double> &values) {
    std::set<uint64_t> cells;
    for (double v : values) cells.insert(static_cast<uint64_t>(v * static_cast<double>(values.size())));
    return cells.size() == values.size();
}

}  // namespace pf::test
