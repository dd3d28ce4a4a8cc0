#include "image/tonemap.h"

#include <algorithm>
#include <cmath>

namespace pf {

namespace {

// Reinhard et al. 2002, eq. 1: delta keeps black pixels from sending the log-average to zero.
constexpr double kLogDelta = 1e-4;
// burn = 1 puts the white point at this fraction of the largest luminance.
constexpr double kMinWhite = 1e-3;

double clean(double v) { return v > 0 ? v : 0.0; }  // also maps NaN to 0

double transfer(double v, double gamma) {
    v = std::min(clean(v), 1.0);
    return gamma == -1.0 ? linearToSrgb(v) : std::pow(v, 1.0 / gamma);
}

}  // namespace

std::vector<double> toneMap(const Bitmap &img, const ToneMap &t) {
    std::vector<double> out(img.rgb.size());
    const size_t pixels = img.rgb.size() / 3;
    const auto luminance = [&](size_t p) {
        return clean(Spectrum(clean(img.rgb[3 * p]), clean(img.rgb[3 * p + 1]), clean(img.rgb[3 * p + 2])).luminance());
    };
    if (t.method == ToneMap::Method::Gamma) {
        const double scale = std::exp2(t.exposure);
        for (size_t i = 0; i < out.size(); ++i) out[i] = transfer(img.rgb[i] * scale, t.gamma);
        return out;
    }
    double logSum = 0, maxLum = 0;
    for (size_t p = 0; p < pixels; ++p) {
        const double l = luminance(p);
        logSum += std::log(kLogDelta + l);
        maxLum = std::max(maxLum, l);
    }
    const double average = std::exp(logSum / static_cast<double>(std::max<size_t>(1, pixels)));
    const double scale = t.key / average;
    const double white = std::max(scale * maxLum * std::max(1.0 - t.burn, kMinWhite), 1e-300);
    for (size_t p = 0; p < pixels; ++p) {
        const double lw = luminance(p), l = scale * lw;
        const double ld = l * (1 + l / (white * white)) / (1 + l);
        const double ratio = lw > 0 ? ld / lw : 0.0;
        for (size_t c = 0; c < 3; ++c) out[3 * p + c] = transfer(img.rgb[3 * p + c] * ratio, t.gamma);
    }
    return out;
}

}  // namespace pf
