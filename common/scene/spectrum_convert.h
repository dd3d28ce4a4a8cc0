// Conversion of spectral scene inputs (<spectrum> wavelength lists, <blackbody>) to the linear sRGB
// values pathfarm renders with, following Mitsuba 0.6 compiled in RGB mode: the spectrum is
// integrated against the CIE 1931 2-degree colour matching functions, normalized by the integral of
// y-bar, and mapped from XYZ to linear sRGB (Rec. 709 primaries, D65 white).
#pragma once
#include <utility>
#include <vector>

#include "core/spectrum.h"
#include "core/vector.h"

namespace pf {

// A spectrum given as (wavelength in nm, value) samples with strictly increasing wavelengths,
// linearly interpolated between samples and zero outside them (Mitsuba's zeroExtend).
using SampledSpectrum = std::vector<std::pair<double, double>>;

// CIE XYZ of a sampled spectrum, normalized so that the constant spectrum 1 has Y = 1.
// Throws std::invalid_argument if the wavelengths are not strictly increasing or not positive.
Vec3 spectrumToXYZ(const SampledSpectrum &spectrum);

// Linear sRGB from CIE XYZ.
Spectrum xyzToLinearRGB(const Vec3 &xyz);

// Linear sRGB of a reflectance or emission spectrum given as samples (the <spectrum> element's
// "wavelength:value" lists). Unlike Mitsuba 0.6, the result is white-balanced so that a constant
// spectrum c gives the grey (c, c, c), exactly what a single-valued <spectrum value="c"/> gives;
// without it, the equal-energy spectrum would come out slightly pink (illuminant E is not the D65
// white of sRGB). Negative components are clamped to zero, as Mitsuba does.
Spectrum sampledSpectrumToRGB(const SampledSpectrum &spectrum);

// Linear sRGB of a black body at `temperatureK` (Planck's law in W m^-2 sr^-1 nm^-1), as Mitsuba 0.6's
// <blackbody> element computes it: the radiance in physical units, not white-balanced, so 6500 K comes
// out nearly neutral. Throws std::invalid_argument unless the temperature is positive and finite.
Spectrum blackbodyToRGB(double temperatureK);

}  // namespace pf
