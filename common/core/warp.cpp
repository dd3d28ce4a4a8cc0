#include "core/warp.h"

#include "core/sincos.h"

namespace pf::warp {

namespace {

// Shirley and Chiu 1997: the angle is (pi/4) b/a in the octants around the x axis and pi/2 - (pi/4) a/b in
// those around y, whose cosine and sine are the sine and cosine of (pi/4) a/b. The octant is chosen without
// a branch: for uniform numbers it is a coin toss that the branch predictor loses half the time.
// `radius2` is the point's squared distance from the centre, r^2 of the larger coordinate.
Vec2 concentricDisk(const Vec2 &u, double &radius2) {
    // Pairs of doubles in vector registers (GCC and Clang vector extensions): the comparison yields an
    // all-ones or all-zeros mask in each lane, and `?:` on it selects without leaving the register file.
    using Double2 = double __attribute__((vector_size(16)));
    const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
    const Double2 aa = {a * a, a * a}, bb = {b * b, b * b};
    const auto aroundX = aa > bb;
    const Double2 ab = {a, b}, ba = {b, a};
    const Double2 chosen = aroundX ? ab : ba;  // (r, the other coordinate)
    const double r = chosen[0];
    radius2 = r * r;
    if (r == 0) return {0, 0};  // only at the centre, a = b = 0
    const SinCos phi = sinCosReduced((kPi / 4.0) * (chosen[1] / r));
    const Double2 alongAcross = {r * phi.cos, r * phi.sin}, acrossAlong = {r * phi.sin, r * phi.cos};
    const Double2 p = aroundX ? alongAcross : acrossAlong;
    return {p[0], p[1]};
}

}  // namespace

Vec3 squareToUniformSphere(const Vec2 &u) {
    const double z = 1.0 - 2.0 * u.y;
    const double r = safeSqrt(1.0 - z * z);
    const SinCos phi = sinCos2Pi(u.x);
    return {r * phi.cos, r * phi.sin, z};
}

Vec3 squareToUniformHemisphere(const Vec2 &u) {
    const double z = u.y;
    const double r = safeSqrt(1.0 - z * z);
    const SinCos phi = sinCos2Pi(u.x);
    return {r * phi.cos, r * phi.sin, z};
}

Vec3 squareToCosineHemisphere(const Vec2 &u) {
    // Malley's method. The height comes from the disk radius, known before the angle's series, rather than
    // from the point's coordinates after it.
    double radius2;
    const Vec2 p = concentricDisk(u, radius2);
    return {p.x, p.y, safeSqrt(1.0 - radius2)};
}

Vec3 squareToUniformCone(const Vec2 &u, double cosCutoff) {
    const double cosTheta = (1.0 - u.y) + u.y * cosCutoff;
    const double sinTheta = safeSqrt(1.0 - cosTheta * cosTheta);
    const SinCos phi = sinCos2Pi(u.x);
    return {phi.cos * sinTheta, phi.sin * sinTheta, cosTheta};
}

double squareToUniformConePdf(const Vec3 &v, double cosCutoff) {
    return v.z >= cosCutoff ? 1.0 / (2.0 * kPi * (1.0 - cosCutoff)) : 0.0;
}

Vec2 squareToUniformDiskConcentric(const Vec2 &u) {
    double radius2;
    return concentricDisk(u, radius2);
}

Vec2 squareToUniformTriangle(const Vec2 &u) {
    const double t = safeSqrt(1.0 - u.x);
    return {1.0 - t, t * u.y};
}

Vec2 squareToStdNormal(const Vec2 &u) {
    const double r = std::sqrt(-2.0 * std::log(std::max(1.0 - u.x, 1e-300)));
    const SinCos phi = sinCos2Pi(u.y);
    return {r * phi.cos, r * phi.sin};
}

}  // namespace pf::warp
