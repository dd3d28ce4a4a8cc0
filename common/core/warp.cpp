#include "core/warp.h"

#include "core/sincos.h"

namespace pf::warp {

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
    const Vec2 p = squareToUniformDiskConcentric(u);
    return {p.x, p.y, safeSqrt(1.0 - p.x * p.x - p.y * p.y)};
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
    const double a = 2.0 * u.x - 1.0, b = 2.0 * u.y - 1.0;
    if (a == 0 && b == 0) return {0, 0};
    // Shirley and Chiu 1997: the angle is (pi/4) b/a in the octants around the x axis and pi/2 - (pi/4) a/b
    // in those around y, whose cosine and sine are the sine and cosine of (pi/4) a/b.
    if (a * a > b * b) {
        const SinCos phi = sinCosReduced((kPi / 4.0) * (b / a));
        return {a * phi.cos, a * phi.sin};
    }
    const SinCos phi = sinCosReduced((kPi / 4.0) * (a / b));
    return {b * phi.sin, b * phi.cos};
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
