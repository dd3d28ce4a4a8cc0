#include "emitter/sunsky/sun_disk.h"

#include <cmath>

#include "core/warp.h"

namespace pf::sunsky {

double coneSolidAngle(double halfAngle) {
    const double s = std::sin(0.5 * halfAngle);
    return 4.0 * kPi * s * s;
}

SunDisk::SunDisk(const Vec3 &direction, double halfAngle, const Spectrum &irradiance)
    : frame_(normalize(direction)),
      cosHalfAngle_(std::cos(halfAngle)),
      solidAngle_(coneSolidAngle(halfAngle)),
      radiance_(irradiance / solidAngle_) {}

Vec3 SunDisk::sample(const Vec2 &u, double &pdf) const {
    pdf = 1.0 / solidAngle_;
    return normalize(frame_.toWorld(warp::squareToUniformCone(u, cosHalfAngle_)));
}

}  // namespace pf::sunsky
