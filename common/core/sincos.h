// Sine and cosine of sampled angles. Warps turn a uniform number into an angle (phi = 2 pi u, or a
// concentric-disk angle within an octant), so they never need the C library's reduction of arbitrary
// arguments: the reduction here is exact, done in turns, and what is left is a short series. On the 2-core
// development machine glibc's sincos took 18 ns a call (4% of a `path` profile, issue 17); the series
// takes 4 ns and agrees with it to an ulp.
#pragma once
#include <cstdint>

#include "core/math.h"

namespace pf {

struct SinCos {
    double sin, cos;
};

// sin t and cos t for |t| <= pi/4: their Maclaurin series (Abramowitz and Stegun 4.3.65 and 4.3.66) through
// t^15 and t^16. The first terms left out, t^17/17! and t^18/18!, stay below 5e-17 there, less than half an
// ulp of either result (|sin t| >= 0.7 |t| and cos t >= 0.7 on that interval).
inline SinCos sinCosReduced(double t) {
    // The series' coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!, of polynomials in t^2.
    constexpr double kSin[] = {1.0,
                               -1.0 / 6.0,
                               1.0 / 120.0,
                               -1.0 / 5040.0,
                               1.0 / 362880.0,
                               -1.0 / 39916800.0,
                               1.0 / 6227020800.0,
                               -1.0 / 1307674368000.0};
    constexpr double kCos[] = {1.0,
                               -1.0 / 2.0,
                               1.0 / 24.0,
                               -1.0 / 720.0,
                               1.0 / 40320.0,
                               -1.0 / 3628800.0,
                               1.0 / 479001600.0,
                               -1.0 / 87178291200.0,
                               1.0 / 20922789888000.0};
    // The tails beyond the first terms by Estrin's scheme, not Horner's rule: the same sums grouped in pairs,
    // so that most multiplies are independent. Horner's chain of eight multiply-adds per series was the
    // latency of a cosine-weighted direction (7.5% of a `path` profile on cornell-box, issue 17). The leading
    // terms, t and 1 - t^2/2, are added last so that the tails' rounding stays below their ulp.
    const double x = t * t, x2 = x * x, x4 = x2 * x2;
    const double sinTail =
        ((kSin[1] + kSin[2] * x) + (kSin[3] + kSin[4] * x) * x2) + ((kSin[5] + kSin[6] * x) + kSin[7] * x2) * x4;
    const double cosTail =
        ((kCos[2] + kCos[3] * x) + (kCos[4] + kCos[5] * x) * x2) + ((kCos[6] + kCos[7] * x) + kCos[8] * x2) * x4;
    return {t + (t * x) * sinTail, (kCos[0] + kCos[1] * x) + x2 * cosTail};
}

// sin and cos of 2 pi u, for |u| < 2^49. In quarter turns q = 4u (exact), the nearest whole quarter k and
// the rest f = q - k (exact, |f| <= 1/2) give the angle k pi/2 + f pi/2, so the only rounding before the
// series is that of f pi/2: more accurate than sin(2 pi u), whose product 2 pi u already rounds.
inline SinCos sinCos2Pi(double u) {
    const double q = 4.0 * u;
    // Adding and subtracting 1.5 * 2^52 rounds q to the nearest integer (ties to even) with two additions,
    // where std::nearbyint is a library call without SSE4.1.
    constexpr double kRound = 0x1.8p52;
    const double k = (q + kRound) - kRound;
    const SinCos r = sinCosReduced((q - k) * (kPi / 2.0));
    switch (static_cast<int64_t>(k) & 3) {
        case 0:
            return r;
        case 1:
            return {r.cos, -r.sin};
        case 2:
            return {-r.sin, -r.cos};
        default:
            return {-r.cos, r.sin};
    }
}

}  // namespace pf
