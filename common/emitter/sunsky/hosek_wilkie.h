// The Hosek-Wilkie sky model: L. Hosek and A. Wilkie, "An Analytic Model for Full Spectral Sky-Dome
// Radiance", ACM Transactions on Graphics 31(4), 2012. For one channel (a wavelength or a tristimulus
// component), a turbidity, a ground albedo and a solar elevation, the model "cooks" nine coefficients and
// a zenith radiance from Bezier splines in the tabulated data; the radiance of a sky direction then
// follows from the extended Perez formula in its zenith angle theta and its angle gamma to the sun.
#pragma once
#include <array>

namespace pf::sunsky {

// A Hosek-Wilkie dataset, laid out as data/sunsky/README.md describes: per channel, 2 albedos x 10
// turbidities x 6 control points x 9 coefficients (A, B, C, D, E, F, G, I, H: I before H), and 2 x 10 x 6
// radiance control points.
struct HosekDataset {
    const double *coefficients;
    const double *radiances;
    int channels;
};

// The RGB dataset compiled into pathfarm (tables.cpp). Its values are integrals against linear sRGB
// matching functions, in W m^-2 sr^-1 (see sky.h for the scale Mitsuba puts them on).
HosekDataset hosekRGB();

class HosekChannel {
public:
    // turbidity in [1, 10], albedo in [0, 1], solarElevation in radians in [0, pi/2].
    HosekChannel(const HosekDataset &data, int channel, double turbidity, double albedo, double solarElevation);

    // Radiance for a view direction at zenith angle theta (cos theta > 0) and at angle gamma to the sun.
    double radiance(double theta, double gamma) const;

private:
    std::array<double, 9> coefficients_{};
    double zenithRadiance_ = 0;
};

}  // namespace pf::sunsky
