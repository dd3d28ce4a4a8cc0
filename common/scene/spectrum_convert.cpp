#include "scene/spectrum_convert.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace pf {

namespace {

// CIE 1931 2-degree standard observer colour matching functions (x-bar, y-bar, z-bar), tabulated by
// the CIE at 5 nm from 380 to 780 nm (CIE 15:2004, table T.4). Beyond this range the functions are
// below 1e-4 of their peaks, so truncating there changes no colour visibly.
constexpr double kCieStart = 380.0, kCieEnd = 780.0, kCieStep = 5.0;
constexpr int kCieSamples = 81;
constexpr std::array<std::array<double, 3>, kCieSamples> kCie = {{
    {0.001368, 0.000039, 0.006450}, {0.002236, 0.000064, 0.010550}, {0.004243, 0.000120, 0.020050},
    {0.007650, 0.000217, 0.036210}, {0.014310, 0.000396, 0.067850}, {0.023190, 0.000640, 0.110200},
    {0.043510, 0.001210, 0.207400}, {0.077630, 0.002180, 0.371300}, {0.134380, 0.004000, 0.645600},
    {0.214770, 0.007300, 1.039050}, {0.283900, 0.011600, 1.385600}, {0.328500, 0.016840, 1.622960},
    {0.348280, 0.023000, 1.747060}, {0.348060, 0.029800, 1.782600}, {0.336200, 0.038000, 1.772110},
    {0.318700, 0.048000, 1.744100}, {0.290800, 0.060000, 1.669200}, {0.251100, 0.073900, 1.528100},
    {0.195360, 0.090980, 1.287640}, {0.142100, 0.112600, 1.041900}, {0.095640, 0.139020, 0.812950},
    {0.057950, 0.169300, 0.616200}, {0.032010, 0.208020, 0.465180}, {0.014700, 0.258600, 0.353300},
    {0.004900, 0.323000, 0.272000}, {0.002400, 0.407300, 0.212300}, {0.009300, 0.503000, 0.158200},
    {0.029100, 0.608200, 0.111700}, {0.063270, 0.710000, 0.078250}, {0.109600, 0.793200, 0.057250},
    {0.165500, 0.862000, 0.042160}, {0.225750, 0.914850, 0.029840}, {0.290400, 0.954000, 0.020300},
    {0.359700, 0.980300, 0.013400}, {0.433450, 0.994950, 0.008750}, {0.512050, 1.000000, 0.005750},
    {0.594500, 0.995000, 0.003900}, {0.678400, 0.978600, 0.002750}, {0.762100, 0.952000, 0.002100},
    {0.842500, 0.915400, 0.001800}, {0.916300, 0.870000, 0.001650}, {0.978600, 0.816300, 0.001400},
    {1.026300, 0.757000, 0.001100}, {1.056700, 0.694900, 0.001000}, {1.062200, 0.631000, 0.000800},
    {1.045600, 0.566800, 0.000600}, {1.002600, 0.503000, 0.000340}, {0.938400, 0.441200, 0.000240},
    {0.854450, 0.381000, 0.000190}, {0.751400, 0.321000, 0.000100}, {0.642400, 0.265000, 0.000050},
    {0.541900, 0.217000, 0.000030}, {0.447900, 0.175000, 0.000020}, {0.360800, 0.138200, 0.000010},
    {0.283500, 0.107000, 0.000000}, {0.218700, 0.081600, 0.000000}, {0.164900, 0.061000, 0.000000},
    {0.121200, 0.044580, 0.000000}, {0.087400, 0.032000, 0.000000}, {0.063600, 0.023200, 0.000000},
    {0.046770, 0.017000, 0.000000}, {0.032900, 0.011920, 0.000000}, {0.022700, 0.008210, 0.000000},
    {0.015840, 0.005723, 0.000000}, {0.011359, 0.004102, 0.000000}, {0.008111, 0.002929, 0.000000},
    {0.005790, 0.002091, 0.000000}, {0.004109, 0.001484, 0.000000}, {0.002899, 0.001047, 0.000000},
    {0.002049, 0.000740, 0.000000}, {0.001440, 0.000520, 0.000000}, {0.001000, 0.000361, 0.000000},
    {0.000690, 0.000249, 0.000000}, {0.000476, 0.000172, 0.000000}, {0.000332, 0.000120, 0.000000},
    {0.000235, 0.000085, 0.000000}, {0.000166, 0.000060, 0.000000}, {0.000117, 0.000042, 0.000000},
    {0.000083, 0.000030, 0.000000}, {0.000059, 0.000021, 0.000000}, {0.000042, 0.000015, 0.000000},
}};

double cieWavelength(int i) { return kCieStart + kCieStep * i; }

// The matching functions, linearly interpolated between the tabulated wavelengths.
Vec3 cmf(double lambda) {
    const double x = std::clamp((lambda - kCieStart) / kCieStep, 0.0, double(kCieSamples - 1));
    const int i = std::min(static_cast<int>(x), kCieSamples - 2);
    const double t = x - i;
    const auto &a = kCie[i], &b = kCie[i + 1];
    return {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
}

// Value of a sampled spectrum at lambda inside its wavelength range.
double evalSampled(const SampledSpectrum &s, double lambda) {
    const auto it = std::lower_bound(s.begin(), s.end(), lambda,
                                     [](const std::pair<double, double> &p, double l) { return p.first < l; });
    if (it == s.begin()) return it->second;
    if (it == s.end()) return s.back().second;
    const auto &[l1, v1] = *it;
    const auto &[l0, v0] = *(it - 1);
    return v0 + (v1 - v0) * (lambda - l0) / (l1 - l0);
}

// Integral of spectrum * matching functions. Between consecutive breakpoints (the table's wavelengths
// and the spectrum's own) both factors are linear, so Simpson's rule on each piece is exact:
// int_a^b f g = (b - a) / 6 * (2 f_a g_a + f_a g_b + f_b g_a + 2 f_b g_b).
Vec3 integrateCmf(const SampledSpectrum &s) {
    const double lo = std::max(kCieStart, s.front().first), hi = std::min(kCieEnd, s.back().first);
    if (!(lo < hi)) return Vec3(0.0);
    std::vector<double> cuts = {lo, hi};
    for (int i = 0; i < kCieSamples; ++i)
        if (cieWavelength(i) > lo && cieWavelength(i) < hi) cuts.push_back(cieWavelength(i));
    for (const auto &sample : s)
        if (sample.first > lo && sample.first < hi) cuts.push_back(sample.first);
    std::sort(cuts.begin(), cuts.end());
    cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());

    Vec3 sum(0.0);
    for (size_t i = 0; i + 1 < cuts.size(); ++i) {
        const double a = cuts[i], b = cuts[i + 1];
        const double fa = evalSampled(s, a), fb = evalSampled(s, b);
        const Vec3 ga = cmf(a), gb = cmf(b);
        sum += (b - a) / 6.0 * ((2.0 * fa + fb) * ga + (fa + 2.0 * fb) * gb);
    }
    return sum;
}

const SampledSpectrum &equalEnergy() {
    static const SampledSpectrum e = {{kCieStart, 1.0}, {kCieEnd, 1.0}};
    return e;
}

}  // namespace

Vec3 spectrumToXYZ(const SampledSpectrum &spectrum) {
    if (spectrum.size() < 2) throw std::invalid_argument("a sampled spectrum needs at least two wavelengths");
    for (size_t i = 0; i < spectrum.size(); ++i) {
        if (!(spectrum[i].first > 0) || !std::isfinite(spectrum[i].first) || !std::isfinite(spectrum[i].second))
            throw std::invalid_argument("spectrum samples must be finite with positive wavelengths");
        if (i > 0 && !(spectrum[i].first > spectrum[i - 1].first))
            throw std::invalid_argument("spectrum wavelengths must be strictly increasing");
    }
    // Mitsuba's CIE_normalization: the constant spectrum 1 has luminance Y = 1.
    static const double yIntegral = integrateCmf(equalEnergy()).y;
    return integrateCmf(spectrum) / yIntegral;
}

// XYZ to linear sRGB (IEC 61966-2-1 primaries, D65 white); the matrix of Mitsuba 0.6's
// Spectrum::fromXYZ and pbrt-v3's XYZToRGB.
Spectrum xyzToLinearRGB(const Vec3 &c) {
    return {3.240479 * c.x - 1.537150 * c.y - 0.498535 * c.z, -0.969256 * c.x + 1.875991 * c.y + 0.041556 * c.z,
            0.055648 * c.x - 0.204043 * c.y + 1.057311 * c.z};
}

Spectrum sampledSpectrumToRGB(const SampledSpectrum &spectrum) {
    static const Spectrum white = xyzToLinearRGB(spectrumToXYZ(equalEnergy()));
    return clampNonNegative(xyzToLinearRGB(spectrumToXYZ(spectrum)) / white);
}

Spectrum blackbodyToRGB(double temperatureK) {
    if (!(temperatureK > 0) || !std::isfinite(temperatureK))
        throw std::invalid_argument("black body temperature must be positive");
    // Planck's law with the SI-defining constants (2019 redefinition).
    constexpr double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23;
    SampledSpectrum s(kCieSamples);
    for (int i = 0; i < kCieSamples; ++i) {
        const double lambda = cieWavelength(i) * 1e-9;
        const double lambda5 = lambda * lambda * lambda * lambda * lambda;
        // Radiance per metre of wavelength, times 1e-9 for per nanometre (Mitsuba's unit).
        const double radiance = 2.0 * h * c * c / (lambda5 * std::expm1(h * c / (lambda * k * temperatureK))) * 1e-9;
        s[i] = {cieWavelength(i), radiance};
    }
    return clampNonNegative(xyzToLinearRGB(spectrumToXYZ(s)));
}

}  // namespace pf
