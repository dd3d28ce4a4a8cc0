// The local frame of the daylight emitters (sun, sky, sunsky), as Mitsuba 0.6 defines it: +Y is the
// zenith, east is +X, north is -Z and south +Z. A direction is given by its zenith angle theta and its
// azimuth phi, measured from north towards east (the convention of the solar position algorithm), so
// that an azimuth of 90 degrees is east. toWorld maps this frame to the scene (Z-up scenes rotate it by
// 90 degrees about X). See data/sunsky/MITSUBA_USAGE.md §2.
#pragma once
#include <cmath>

#include "core/math.h"
#include "core/vector.h"

namespace pf::sunsky {

struct SphericalCoordinates {
    double theta = 0;  // zenith angle in radians (0 = straight up)
    double phi = 0;    // azimuth in radians from north (-Z) towards east (+X), in [0, 2 pi)
};

inline Vec3 toSphere(const SphericalCoordinates &c) {
    const double sinTheta = std::sin(c.theta);
    return {std::sin(c.phi) * sinTheta, std::cos(c.theta), -std::cos(c.phi) * sinTheta};
}

// Inverse of toSphere for a unit vector. atan2 for theta keeps full precision near the zenith, where acos
// would lose half the digits.
inline SphericalCoordinates fromSphere(const Vec3 &v) {
    double phi = std::atan2(v.x, -v.z);
    if (phi < 0) phi += 2.0 * kPi;
    return {std::atan2(std::hypot(v.x, v.z), v.y), phi};
}

}  // namespace pf::sunsky
