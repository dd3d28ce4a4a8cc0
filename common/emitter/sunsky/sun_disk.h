// The solar disk as an emitter at infinity: a cone of directions around the sun of constant radiance,
// sampled uniformly within the cone. Mitsuba 0.6 instead splats the disk into its environment map at the
// map's resolution (a blurred patch about a pixel across); both deliver the same irradiance.
#pragma once
#include "core/frame.h"
#include "core/spectrum.h"

namespace pf::sunsky {

class SunDisk {
public:
    SunDisk() = default;
    // direction: unit vector towards the sun's centre; halfAngle: cone half-angle in radians (> 0);
    // irradiance: what the whole disk delivers to a surface facing it.
    SunDisk(const Vec3 &direction, double halfAngle, const Spectrum &irradiance);

    Spectrum eval(const Vec3 &v) const { return inside(v) ? radiance_ : Spectrum(0.0); }
    Vec3 sample(const Vec2 &u, double &pdf) const;
    double pdf(const Vec3 &v) const { return inside(v) ? 1.0 / solidAngle_ : 0.0; }
    // The integral of the radiance over the sphere: the irradiance.
    Spectrum integral() const { return radiance_ * solidAngle_; }
    const Vec3 &direction() const { return frame_.n; }
    double solidAngle() const { return solidAngle_; }

private:
    bool inside(const Vec3 &v) const { return dot(v, frame_.n) >= cosHalfAngle_; }

    Frame frame_;
    double cosHalfAngle_ = 1, solidAngle_ = 0;
    Spectrum radiance_;
};

// The solid angle 2 pi (1 - cos a) of a cone of half-angle a, written as 4 pi sin^2(a / 2) so that it
// keeps its digits for a cone as narrow as the sun's.
double coneSolidAngle(double halfAngle);

}  // namespace pf::sunsky
