// Reconstruction filters of Mitsuba 0.6 (src/rfilters/*.cpp), evaluated directly rather than through
// Mitsuba's 32-entry lookup table: the table only saves an exp() per tap, and exact values keep the
// filters smooth (pbrt-v3 §7.8.1 discusses the same trade-off).
#include "image/rfilter.h"

#include <cmath>

#include "core/math.h"

namespace pf {

int ReconstructionFilter::borderSize() const { return std::max(0, static_cast<int>(std::ceil(radius_ - 0.5))); }

BoxFilter::BoxFilter(double radius) { radius_ = radius; }

// Closed at both ends: a sample exactly on a pixel edge counts for both neighbours, so none is lost
// (Mitsuba pads the radius by 1e-5 for the same reason).
double BoxFilter::eval(double x) const { return std::abs(x) <= radius_ ? 1.0 : 0.0; }

TentFilter::TentFilter() { radius_ = 1.0; }

double TentFilter::eval(double x) const { return std::max(0.0, 1.0 - std::abs(x) / radius_); }

// A Gaussian truncated at 4 standard deviations and shifted down by its value there, so that it falls
// continuously to zero at the radius (Mitsuba's gaussian.cpp).
GaussianFilter::GaussianFilter(double stddev) : stddev_(stddev), alpha_(-1.0 / (2.0 * stddev * stddev)), bias_(0) {
    radius_ = 4.0 * stddev;
    bias_ = std::exp(alpha_ * radius_ * radius_);
}

double GaussianFilter::eval(double x) const { return std::max(0.0, std::exp(alpha_ * x * x) - bias_); }

MitchellNetravaliFilter::MitchellNetravaliFilter(double B, double C) : B_(B), C_(C) { radius_ = 2.0; }

// Mitchell and Netravali 1988, eq. 8 (pbrt-v3 §7.8.1): a piecewise cubic on |x| < 1 and 1 <= |x| < 2.
double MitchellNetravaliFilter::eval(double x) const {
    x = std::abs(x);
    const double x2 = x * x, x3 = x2 * x;
    if (x < 1.0) return ((12 - 9 * B_ - 6 * C_) * x3 + (-18 + 12 * B_ + 6 * C_) * x2 + (6 - 2 * B_)) / 6.0;
    if (x < 2.0)
        return ((-B_ - 6 * C_) * x3 + (6 * B_ + 30 * C_) * x2 + (-12 * B_ - 48 * C_) * x + (8 * B_ + 24 * C_)) / 6.0;
    return 0.0;
}

LanczosSincFilter::LanczosSincFilter(int lobes) { radius_ = lobes; }

// sinc(x) windowed by sinc(x / lobes) (pbrt-v3 §7.8.1, Mitsuba's lanczos.cpp).
double LanczosSincFilter::eval(double x) const {
    x = std::abs(x);
    if (x > radius_) return 0.0;
    if (x < 1e-6) return 1.0;  // both sincs are 1 - O(x^2) here
    const double a = kPi * x, b = a / radius_;
    return std::sin(a) * std::sin(b) / (a * b);
}

}  // namespace pf
