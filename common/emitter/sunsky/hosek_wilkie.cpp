#include "emitter/sunsky/hosek_wilkie.h"

#include <cmath>

#include "core/math.h"
#include "emitter/sunsky/tables.h"

namespace pf::sunsky {

namespace {

constexpr int kCoefficients = 9, kControlPoints = 6, kTurbidities = 10;

// The quintic Bezier curve of one (albedo, turbidity) block at spline parameter s: the model tabulates
// each quantity at 6 control points in s = (elevation / (pi/2))^(1/3), which spends more of the spline
// on low suns, where the sky changes fastest (Hosek & Wilkie 2012, the fitting of the model).
double bezier(const double *block, int stride, double s) {
    static constexpr double kBinomial[kControlPoints] = {1, 5, 10, 10, 5, 1};
    double sum = 0;
    for (int k = 0; k < kControlPoints; ++k)
        sum += kBinomial[k] * std::pow(1.0 - s, kControlPoints - 1 - k) * std::pow(s, k) * block[k * stride];
    return sum;
}

// Bilinear blend in albedo (0 and 1 are tabulated) and turbidity (integers 1..10) of a quantity whose
// (albedo, turbidity) block starts at table + blockSize * (turbidity - 1 + 10 * albedo).
double interpolate(const double *table, int blockSize, int stride, double turbidity, double albedo, double s) {
    const int t0 = static_cast<int>(turbidity);
    const double r = turbidity - t0;
    const auto block = [&](int a, int t) {
        return bezier(table + blockSize * ((t - 1) + kTurbidities * a), stride, s);
    };
    double value = (1.0 - albedo) * (1.0 - r) * block(0, t0) + albedo * (1.0 - r) * block(1, t0);
    if (t0 < kTurbidities) value += (1.0 - albedo) * r * block(0, t0 + 1) + albedo * r * block(1, t0 + 1);
    return value;
}

}  // namespace

HosekDataset hosekRGB() { return {kHosekRGBCoeffs, kHosekRGBRadiance, 3}; }

HosekChannel::HosekChannel(const HosekDataset &data, int channel, double turbidity, double albedo,
                           double solarElevation) {
    const double s = std::cbrt(solarElevation / (0.5 * kPi));
    constexpr int coefficientBlock = kCoefficients * kControlPoints;
    const double *coefficients = data.coefficients + channel * 2 * kTurbidities * coefficientBlock;
    for (int i = 0; i < kCoefficients; ++i)
        coefficients_[i] = interpolate(coefficients + i, coefficientBlock, kCoefficients, turbidity, albedo, s);
    zenithRadiance_ = interpolate(data.radiances + channel * 2 * kTurbidities * kControlPoints, kControlPoints, 1,
                                  turbidity, albedo, s);
}

// The extended Perez formula (Hosek & Wilkie 2012, the model's radiance distribution): the Perez et al. 1993 gradation
// and indicatrix terms, plus a Henyey-Greenstein-like lobe G chi(H, gamma) for aerosol (Mie) scattering around the sun
// and I sqrt(cos theta) for the zenith brightening; the product scales the zenith radiance L_M.
double HosekChannel::radiance(double theta, double gamma) const {
    const auto &[A, B, C, D, E, F, G, I, H] = coefficients_;  // the tables' order: I before H
    const double cosGamma = std::cos(gamma), cosTheta = std::cos(theta);
    const double mie = (1.0 + cosGamma * cosGamma) / std::pow(1.0 + H * H - 2.0 * H * cosGamma, 1.5);
    const double gradation = 1.0 + A * std::exp(B / (cosTheta + 0.01));
    const double indicatrix = C + D * std::exp(E * gamma) + F * cosGamma * cosGamma + G * mie + I * std::sqrt(cosTheta);
    return gradation * indicatrix * zenithRadiance_;
}

}  // namespace pf::sunsky
