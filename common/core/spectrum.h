// Linear RGB "spectrum" (Mitsuba 0.6 in its default RGB mode). Spectral inputs are converted to
// linear sRGB by the scene loader (scene/spectrum_convert.h).
#pragma once
#include <algorithm>
#include <cmath>

namespace pf {

struct Spectrum {
    double r = 0, g = 0, b = 0;
    Spectrum() = default;
    explicit Spectrum(double v) : r(v), g(v), b(v) {}
    Spectrum(double r_, double g_, double b_) : r(r_), g(g_), b(b_) {}
    Spectrum operator+(const Spectrum &o) const { return {r + o.r, g + o.g, b + o.b}; }
    Spectrum operator-(const Spectrum &o) const { return {r - o.r, g - o.g, b - o.b}; }
    Spectrum operator*(const Spectrum &o) const { return {r * o.r, g * o.g, b * o.b}; }
    Spectrum operator/(const Spectrum &o) const {
        return {o.r != 0 ? r / o.r : 0, o.g != 0 ? g / o.g : 0, o.b != 0 ? b / o.b : 0};
    }
    Spectrum operator*(double s) const { return {r * s, g * s, b * s}; }
    Spectrum operator/(double s) const { return *this * (1.0 / s); }
    Spectrum &operator+=(const Spectrum &o) { r += o.r; g += o.g; b += o.b; return *this; }
    Spectrum &operator*=(const Spectrum &o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
    Spectrum &operator*=(double s) { r *= s; g *= s; b *= s; return *this; }
    bool operator==(const Spectrum &o) const { return r == o.r && g == o.g && b == o.b; }
    double operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
    double &operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
    bool isBlack() const { return r == 0 && g == 0 && b == 0; }
    bool isFinite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
    bool isValid() const { return isFinite() && r >= 0 && g >= 0 && b >= 0; }
    double max() const { return std::max(r, std::max(g, b)); }
    double min() const { return std::min(r, std::min(g, b)); }
    double average() const { return (r + g + b) / 3.0; }
    // Luminance Y of linear sRGB (Rec. 709 primaries, D65), the π of every MLT-type chain (§2.2).
    double luminance() const { return 0.212671 * r + 0.715160 * g + 0.072169 * b; }
};

inline Spectrum operator*(double s, const Spectrum &v) { return v * s; }
inline Spectrum sqrt(const Spectrum &s) { return {std::sqrt(s.r), std::sqrt(s.g), std::sqrt(s.b)}; }
inline Spectrum exp(const Spectrum &s) { return {std::exp(s.r), std::exp(s.g), std::exp(s.b)}; }
inline Spectrum clampNonNegative(const Spectrum &s) {
    return {std::max(0.0, s.r), std::max(0.0, s.g), std::max(0.0, s.b)};
}

// sRGB transfer functions (IEC 61966-2-1).
inline double srgbToLinear(double v) {
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}
inline double linearToSrgb(double v) {
    return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

}  // namespace pf
