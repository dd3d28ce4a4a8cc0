// The sine and cosine of sampled angles (core/sincos.h) against long-double references: within a few
// units in the last place everywhere, and exact at whole quarter turns.
#include <gtest/gtest.h>

#include <cmath>

#include "core/rng.h"
#include "core/sincos.h"

namespace pf {
namespace {

constexpr long double kPiL = 3.141592653589793238462643383279502884L;

// |x - reference| in units of 2^-53, the spacing of doubles in [0.5, 1): an absolute measure, since both
// results lie in [-1, 1] and a sine near zero is compared at the scale of its argument's rounding.
double ulpsAbs(double x, long double reference) {
    return static_cast<double>(std::fabs(static_cast<long double>(x) - reference) * 0x1.0p53L);
}

TEST(SinCos, ReducedSeriesMatchesTheLibraryOnItsInterval) {
    PCG32 rng(7, 1);
    double worstSin = 0, worstCos = 0, worstSinRel = 0;
    for (int i = 0; i < 200000; ++i) {
        const double t = (2.0 * rng.nextDouble() - 1.0) * (kPi / 4.0);
        const SinCos r = sinCosReduced(t);
        const long double s = std::sin(static_cast<long double>(t)), c = std::cos(static_cast<long double>(t));
        worstSin = std::max(worstSin, ulpsAbs(r.sin, s));
        worstCos = std::max(worstCos, ulpsAbs(r.cos, c));
        if (t != 0) worstSinRel = std::max(worstSinRel, static_cast<double>(std::fabs((r.sin - s) / s)));
    }
    // Both ends of the interval, where the series' truncation error is largest.
    for (const double t : {kPi / 4.0, -kPi / 4.0}) {
        const SinCos r = sinCosReduced(t);
        worstSin = std::max(worstSin, ulpsAbs(r.sin, std::sin(static_cast<long double>(t))));
        worstCos = std::max(worstCos, ulpsAbs(r.cos, std::cos(static_cast<long double>(t))));
    }
    EXPECT_LE(worstSin, 1.5);
    EXPECT_LE(worstCos, 1.5);
    EXPECT_LE(worstSinRel, 3e-16);  // small angles keep their relative precision
    EXPECT_EQ(sinCosReduced(0.0).sin, 0.0);
    EXPECT_EQ(sinCosReduced(0.0).cos, 1.0);
}

TEST(SinCos, TurnsCoverEveryQuadrantAndWholeTurns) {
    PCG32 rng(8, 2);
    double worst = 0;
    for (int i = 0; i < 200000; ++i) {
        const double u = (rng.nextDouble() - 0.5) * 8.0;  // four turns either way
        const SinCos r = sinCos2Pi(u);
        const long double angle = 2.0L * kPiL * static_cast<long double>(u);
        worst = std::max({worst, ulpsAbs(r.sin, std::sin(angle)), ulpsAbs(r.cos, std::cos(angle))});
    }
    EXPECT_LE(worst, 2.0);
    // Whole quarter turns are exact (std::cos(2 pi 0.25) is 6e-17, not 0).
    const double quarters[][3] = {{0.0, 0.0, 1.0},   {0.25, 1.0, 0.0}, {0.5, 0.0, -1.0},
                                  {0.75, -1.0, 0.0}, {1.0, 0.0, 1.0},  {-0.25, -1.0, 0.0}};
    for (const auto &q : quarters) {
        const SinCos r = sinCos2Pi(q[0]);
        EXPECT_EQ(r.sin, q[1]) << "u = " << q[0];
        EXPECT_EQ(r.cos, q[2]) << "u = " << q[0];
    }
}

}  // namespace
}  // namespace pf
