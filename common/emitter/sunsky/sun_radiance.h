// The sun's radiance seen through the atmosphere, as Mitsuba 0.6 computes it: the extraterrestrial solar
// spectrum attenuated by Rayleigh scattering, aerosols (from the turbidity), ozone, mixed gases and water
// vapour along the relative air mass of the sun's zenith angle (Preetham, Shirley and Smits, "A Practical
// Analytic Model for Daylight", SIGGRAPH 1999, appendix on the sun's spectral radiance, with the
// transmittances of Iqbal, "An Introduction to Solar Radiation", 1983, pp. 115-132), then converted to linear sRGB.
#pragma once
#include "core/spectrum.h"
#include "scene/spectrum_convert.h"

namespace pf::sunsky {

// Spectral radiance in W m^-2 sr^-1 nm^-1 at 350, 355, ..., 800 nm for a sun at zenith angle theta
// (radians) and the given turbidity, linearly interpolated between the samples and zero outside them.
SampledSpectrum sunSpectrum(double theta, double turbidity);

// The same as linear sRGB (CIE 1931 XYZ normalized by the integral of y-bar, then the sRGB matrix,
// negative components clamped), the per-nanometre scale on which Mitsuba's RGB mode works.
Spectrum sunRadiance(double theta, double turbidity);

// Angular radius of the solar disk: Mitsuba's SUN_APP_RADIUS of 0.5358 degrees is the apparent diameter,
// of which it uses half as the cone half-angle.
constexpr double kSunHalfAngleDegrees = 0.5358 * 0.5;

}  // namespace pf::sunsky
