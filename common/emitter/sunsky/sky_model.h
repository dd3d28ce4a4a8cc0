// The radiance of Mitsuba 0.6's `sky` emitter for a direction of the local frame (horizon_frame.h), and
// its rasterization into a latitude-longitude map (data/sunsky/MITSUBA_USAGE.md §4 and §7).
#pragma once
#include <array>

#include "core/spectrum.h"
#include "emitter/sunsky/horizon_frame.h"
#include "emitter/sunsky/hosek_wilkie.h"
#include "image/bitmap.h"

namespace pf::sunsky {

struct SkyParameters {
    SphericalCoordinates sun;  // the sun's position (unstretched); its zenith angle must be <= pi/2
    double turbidity = 3;      // [1, 10]
    Spectrum albedo{0.2};      // ground albedo per channel, [0, 1]
    double stretch = 1;        // [1, 2]: the sky's zenith angles are divided by it
    bool extend = false;       // fill the lower hemisphere by continuing the horizon
    double scale = 1;
};

class SkyModel {
public:
    explicit SkyModel(const SkyParameters &params);

    // Radiance seen looking along direction `dir`, in Mitsuba's RGB units (W m^-2 sr^-1 nm^-1).
    Spectrum radiance(const SphericalCoordinates &dir) const;

    // The map Mitsuba builds: resolution x resolution/2 pixels, each holding the radiance of its centre.
    Bitmap rasterize(int resolution) const;

    // Hosek's RGB tables integrate radiance against colour matching functions; dividing by the sum of the
    // 1 nm CIE y-bar table (360-830 nm) puts them on the per-nanometre scale of Mitsuba's RGB spectra.
    static constexpr double kRGBToPerNanometre = 1.0 / 106.856980;

private:
    SkyParameters params_;
    std::array<HosekChannel, 3> channels_;
};

}  // namespace pf::sunsky
