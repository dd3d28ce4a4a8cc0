// Scalar helpers and constants shared by the whole renderer.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace pf {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInvPi = 1.0 / kPi;
constexpr double kInvTwoPi = 0.5 / kPi;
constexpr double kInvFourPi = 0.25 / kPi;
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Relative offset used to push secondary rays off surfaces (scaled by the scene extent in Scene).
constexpr double kShadowEpsilon = 1e-4;

inline double clamp(double v, double lo, double hi) { return std::min(std::max(v, lo), hi); }
inline double lerp(double t, double a, double b) { return (1.0 - t) * a + t * b; }
inline double safeSqrt(double v) { return std::sqrt(std::max(0.0, v)); }
inline double safeAcos(double v) { return std::acos(clamp(v, -1.0, 1.0)); }
inline double safeAsin(double v) { return std::asin(clamp(v, -1.0, 1.0)); }
inline double degToRad(double d) { return d * (kPi / 180.0); }
inline double radToDeg(double r) { return r * (180.0 / kPi); }
inline double sqr(double v) { return v * v; }

// Power heuristic with beta = 2 (Veach 1997, eq. 9.13), written in the two-strategy form.
inline double powerHeuristic(double pdfA, double pdfB) {
    const double a = pdfA * pdfA, b = pdfB * pdfB;
    if (a + b == 0.0) return 0.0;
    if (std::isinf(a)) return 1.0;
    return a / (a + b);
}

}  // namespace pf
