#include "emitter/sunsky/sky_model.h"

#include <cmath>

namespace pf::sunsky {

namespace {

// Hosek-Wilkie parameters are per channel: channel i sees the albedo's i-th component.
std::array<HosekChannel, 3> cook(const SkyParameters &p) {
    const double elevation = 0.5 * kPi - p.sun.theta;
    const HosekDataset rgb = hosekRGB();
    return {HosekChannel(rgb, 0, p.turbidity, p.albedo.r, elevation),
            HosekChannel(rgb, 1, p.turbidity, p.albedo.g, elevation),
            HosekChannel(rgb, 2, p.turbidity, p.albedo.b, elevation)};
}

// Mitsuba's Epsilon in its default single-precision build: how far above the horizon an extended sky
// evaluates the model for directions below it.
constexpr double kHorizonEpsilon = 1e-4;

double smoothStep(double v) {
    v = clamp(v, 0.0, 1.0);
    return v * v * (3.0 - 2.0 * v);
}

}  // namespace

SkyModel::SkyModel(const SkyParameters &params) : params_(params), channels_(cook(params)) {}

Spectrum SkyModel::radiance(const SphericalCoordinates &dir) const {
    // stretch > 1 squeezes the model's dome into a narrower cone of zenith angles (an artistic control).
    double theta = dir.theta / params_.stretch;
    if (std::cos(theta) <= 0) {
        if (!params_.extend) return Spectrum(0.0);
        theta = 0.5 * kPi - kHorizonEpsilon;
    }
    // Angle to the sun by the spherical law of cosines, with the (unstretched) sun position.
    const SphericalCoordinates &sun = params_.sun;
    const double cosGamma =
        std::cos(theta) * std::cos(sun.theta) + std::sin(theta) * std::sin(sun.theta) * std::cos(dir.phi - sun.phi);
    const double gamma = safeAcos(cosGamma);
    Spectrum L;
    for (int i = 0; i < 3; ++i) L[i] = channels_[i].radiance(theta, gamma) * kRGBToPerNanometre;
    L = clampNonNegative(L);
    // The extended sky fades smoothly to black at the nadir.
    if (params_.extend) L *= smoothStep(2.0 - 2.0 * dir.theta * kInvPi);
    return L * params_.scale;
}

Bitmap SkyModel::rasterize(int resolution) const {
    Bitmap map(resolution, resolution / 2);
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            map.set(x, y, radiance({kPi * (y + 0.5) / map.height, 2.0 * kPi * (x + 0.5) / map.width}));
    return map;
}

}  // namespace pf::sunsky
