#include "core/warp.h"

#include <array>

namespace pf::warp {

Vec3 squareToUniformSphere(const Vec2 &u) {
    const double z = 1.0 - 2.0 * u.y;
    const double r = safeSqrt(1.0 - z * z);
    const double phi = 2.0 * kPi * u.x;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 squareToUniformHemisphere(const Vec2 &u) {
    const double z = u.y;
    const double r = safeSqrt(1.0 - z * z);
    const double phi = 2.0 * kPi * u.x;
    return {r * std::cos(phi), r * std::sin(phi), z};
}

Vec3 squareToCosineHemisphere(const Vec2 &u) {
    const Vec2 p = squareToUniformDiskConcentric(u);
    return {p.x, p.y, safeSqrt(1.0 - p.x * p.x - p.y * p.y)};
}

Vec3 squareToUniformCone(const Vec2 &u, double cosCutoff) {
    const double cosTheta = (1.0 - u.y) + u.y * cosCutoff;
    const double sinTheta = safeSqrt(1.0 - cosTheta * cosTheta);
    const double phi = 2.0 * kPi * u.x;
    return {std::cos(phi) * sinTheta, std::sin(phi) * sinTheta, cosTheta};
}

double squareToUniformConePdf(const Vec3 &v, double cosCutoff) {
    return v.z >= cosCutoff ? 1.0 / (2.0 * kPi * (1.0 - cosCutoff)) : 0.0;
}

namespace {

// Horner's rule for c[0] + c[1] y + c[2] y^2 + ...
template <size_t N>
double polynomial(double y, const std::array<double, N> &c) {
    double r = c[N - 1];
    for (size_t i = N - 1; i-- > 0;) r = r * y + c[i];
    return r;
}

// sin and cos of x in [-pi/4, pi/4], the only angles the concentric map needs, as Taylor polynomials
// through x^15 and x^16 (coefficients (-1)^k / (2k+1)! and (-1)^k / (2k)!): there the first terms left
// out, |x|^17/17! and |x|^18/18!, are below 6e-17 |sin x| and 3e-18, under half an ulp, so the results
// are within an ulp or two of std::sin and std::cos (test_warp checks). libm's sincos reduces arbitrary
// arguments first and took about 4% of the path tracer's time (issue 17's profile) for the cosine-weighted
// sampling of every diffuse vertex.
constexpr std::array<double, 8> kSinTaylor = {
    1.0, -1.0 / 6, 1.0 / 120, -1.0 / 5040, 1.0 / 362880, -1.0 / 39916800, 1.0 / 6227020800.0, -1.0 / 1307674368000.0};
constexpr std::array<double, 9> kCosTaylor = {1.0,
                                              -1.0 / 2,
                                              1.0 / 24,
                                              -1.0 / 720,
                                              1.0 / 40320,
                                              -1.0 / 3628800,
                                              1.0 / 479001600.0,
                                              -1.0 / 87178291200.0,
                                              1.0 / 20922789888000.0};

double sinQuarterPi(double x) { return x * polynomial(x * x, kSinTaylor); }
double cosQuarterPi(double x) { return polynomial(x * x, kCosTaylor); }

}  // namespace

// Shirley and Chiu 1997, "A low distortion map between disk and square": the wedge |a| > |b| maps to the
// angle phi = pi/4 b/a, the other to phi = pi/2 - pi/4 a/b, i.e. the same angle theta = pi/4 a/b with x
// and y exchanged (cos(pi/2 - theta) = sin theta), so both take sin and cos of |theta| <= pi/4.
Vec2 squareToUniformDiskConcentric(const Vec2 &u) {
    const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
    if (a == 0 && b == 0) return {0, 0};
    if (a * a > b * b) {
        const double theta = (kPi / 4.0) * (b / a);
        return {a * cosQuarterPi(theta), a * sinQuarterPi(theta)};
    }
    const double theta = (kPi / 4.0) * (a / b);
    return {b * sinQuarterPi(theta), b * cosQuarterPi(theta)};
}

Vec2 squareToUniformTriangle(const Vec2 &u) {
    const double t = safeSqrt(1.0 - u.x);
    return {1.0 - t, t * u.y};
}

Vec2 squareToStdNormal(const Vec2 &u) {
    const double r = std::sqrt(-2.0 * std::log(std::max(1.0 - u.x, 1e-300)));
    const double phi = 2.0 * kPi * u.y;
    return {r * std::cos(phi), r * std::sin(phi)};
}

}  // namespace pf::warp
