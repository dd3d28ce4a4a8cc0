// Warping functions from the unit square to common domains, with their densities (pbrt-v3 §13.6,
// Mitsuba's warp namespace). Each is chi-square tested in tests/test_warp.cpp.
#pragma once
#include "core/vector.h"

namespace pf::warp {

Vec3 squareToUniformSphere(const Vec2 &u);
inline double squareToUniformSpherePdf() { return kInvFourPi; }

Vec3 squareToUniformHemisphere(const Vec2 &u);
inline double squareToUniformHemispherePdf(const Vec3 &v) { return v.z >= 0 ? kInvTwoPi : 0.0; }

Vec3 squareToCosineHemisphere(const Vec2 &u);
inline double squareToCosineHemispherePdf(const Vec3 &v) { return v.z > 0 ? v.z * kInvPi : 0.0; }

// Uniform cone about +z with cos(half-angle) = cosCutoff.
Vec3 squareToUniformCone(const Vec2 &u, double cosCutoff);
double squareToUniformConePdf(const Vec3 &v, double cosCutoff);

// Shirley-Chiu concentric map to the unit disk.
Vec2 squareToUniformDiskConcentric(const Vec2 &u);
inline double squareToUniformDiskPdf() { return kInvPi; }

// Barycentric coordinates (b1, b2) uniform on a triangle.
Vec2 squareToUniformTriangle(const Vec2 &u);

// Standard normal pair (Box-Muller), used by the Gaussian reconstruction filter sampler and tests.
Vec2 squareToStdNormal(const Vec2 &u);

}  // namespace pf::warp
