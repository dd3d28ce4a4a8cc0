#include "image/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace pf {

namespace {

const char *const kChannels = "RGB";

// Throws MetricError unless the two images have the same non-empty size and only finite values.
void checkComparable(const Bitmap &image, const Bitmap &reference) {
    for (const auto &[img, role] : {std::pair{&image, "image"}, std::pair{&reference, "reference"}}) {
        if (img->width < 1 || img->height < 1 || img->rgb.size() != static_cast<size_t>(img->width) * img->height * 3)
            throw MetricError(std::string("the ") + role + " is empty or malformed (" + std::to_string(img->width) +
                              "x" + std::to_string(img->height) + ")");
        const auto bad = std::find_if(img->rgb.begin(), img->rgb.end(), [](float v) { return !std::isfinite(v); });
        if (bad != img->rgb.end()) {
            const size_t i = static_cast<size_t>(bad - img->rgb.begin());
            const size_t pixel = i / 3;
            throw MetricError(std::string("the ") + role + " has a non-finite value (" + std::to_string(*bad) +
                              ") at pixel (" + std::to_string(pixel % img->width) + ", " +
                              std::to_string(pixel / img->width) + ") channel " + kChannels[i % 3]);
        }
    }
    if (image.width != reference.width || image.height != reference.height)
        throw MetricError("the image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                          " but the reference is " + std::to_string(reference.width) + "x" +
                          std::to_string(reference.height));
}

// The per-channel term of a metric (see metrics.h); RMSE's term is MSE's.
double channelTerm(Metric m, double a, double b, double eps) {
    const double d = a - b;
    switch (m) {
        case Metric::MSE:
        case Metric::RMSE:
            return d * d;
        case Metric::RelMSE:
            return d * d / (b * b + eps);
        case Metric::MAPE:
            return std::abs(d) / (std::abs(b) + eps);
        case Metric::SMAPE:
            return std::abs(d) / (std::abs(a) + std::abs(b) + eps);
    }
    return 0;
}

// Per-pixel errors of `m` before any root: the mean of the channel terms.
std::vector<double> pixelTerms(const Bitmap &image, const Bitmap &reference, Metric m, double eps) {
    std::vector<double> e(static_cast<size_t>(image.width) * image.height);
    for (size_t p = 0; p < e.size(); ++p) {
        double sum = 0;
        for (size_t c = 0; c < 3; ++c) sum += channelTerm(m, image.rgb[3 * p + c], reference.rgb[3 * p + c], eps);
        e[p] = sum / 3.0;
    }
    return e;
}

// Mean of the values left after discarding the `trimmed` largest.
double trimmedMean(std::vector<double> values, int64_t trimmed) {
    const auto keep = static_cast<std::ptrdiff_t>(values.size()) - trimmed;
    if (trimmed > 0) std::nth_element(values.begin(), values.begin() + keep, values.end());
    return std::accumulate(values.begin(), values.begin() + keep, 0.0) / static_cast<double>(keep);
}

void checkEpsilon(double eps) {
    if (!(eps > 0) || !std::isfinite(eps))
        throw MetricError("the metrics' epsilon must be positive and finite, got " + std::to_string(eps));
}

}  // namespace

std::string metricName(Metric m) {
    switch (m) {
        case Metric::MSE:
            return "mse";
        case Metric::RMSE:
            return "rmse";
        case Metric::RelMSE:
            return "relmse";
        case Metric::MAPE:
            return "mape";
        case Metric::SMAPE:
            return "smape";
    }
    return "";
}

std::string metricDefinition(Metric m, double epsilon) {
    char eps[32];
    std::snprintf(eps, sizeof eps, "%g", epsilon);
    const std::string mean = "mean over pixels and R, G, B channels of ";
    switch (m) {
        case Metric::MSE:
            return mean + "(a - b)^2";
        case Metric::RMSE:
            return "sqrt(MSE)";
        case Metric::RelMSE:
            return mean + "(a - b)^2 / (b^2 + " + eps + ")";
        case Metric::MAPE:
            return mean + "|a - b| / (|b| + " + eps + ")";
        case Metric::SMAPE:
            return mean + "|a - b| / (|a| + |b| + " + eps + ")";
    }
    return "";
}

const std::vector<Metric> &allMetrics() {
    static const std::vector<Metric> all = {Metric::MSE, Metric::RMSE, Metric::RelMSE, Metric::MAPE, Metric::SMAPE};
    return all;
}

double ErrorMetrics::get(Metric m) const {
    switch (m) {
        case Metric::MSE:
            return mse;
        case Metric::RMSE:
            return rmse;
        case Metric::RelMSE:
            return relMse;
        case Metric::MAPE:
            return mape;
        case Metric::SMAPE:
            return smape;
    }
    return 0;
}

ErrorMetrics computeMetrics(const Bitmap &image, const Bitmap &reference, const MetricOptions &options) {
    checkComparable(image, reference);
    checkEpsilon(options.epsilon);
    if (!(options.trimFraction >= 0 && options.trimFraction <= 0.5))
        throw MetricError("the trim fraction must be in [0, 0.5], got " + std::to_string(options.trimFraction));
    ErrorMetrics r;
    r.options = options;
    r.pixels = static_cast<int64_t>(image.width) * image.height;
    r.trimmedPixels = static_cast<int64_t>(std::floor(options.trimFraction * static_cast<double>(r.pixels)));
    const auto mean = [&](Metric m) {
        return trimmedMean(pixelTerms(image, reference, m, options.epsilon), r.trimmedPixels);
    };
    r.mse = mean(Metric::MSE);
    r.rmse = std::sqrt(r.mse);
    r.relMse = mean(Metric::RelMSE);
    r.mape = mean(Metric::MAPE);
    r.smape = mean(Metric::SMAPE);
    return r;
}

double efficiency(double error, double seconds) {
    if (!(error >= 0) || !(seconds > 0) || !std::isfinite(seconds))
        throw std::invalid_argument("efficiency needs an error >= 0 and a positive time, got error " +
                                    std::to_string(error) + " and " + std::to_string(seconds) + " s");
    return 1.0 / (error * seconds);
}

ErrorMap errorMap(const Bitmap &image, const Bitmap &reference, Metric m, double epsilon) {
    checkComparable(image, reference);
    checkEpsilon(epsilon);
    ErrorMap map{image.width, image.height, pixelTerms(image, reference, m, epsilon)};
    if (m == Metric::RMSE)
        for (double &v : map.values) v = std::sqrt(v);
    return map;
}

double quantile(const ErrorMap &map, double q) {
    if (map.values.empty()) throw MetricError("quantile of an empty error map");
    std::vector<double> v = map.values;
    // Nearest rank: the ceil(q n)-th smallest value (1-based).
    const double rank = std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size()));
    const size_t k = rank < 1 ? 0 : std::min(v.size() - 1, static_cast<size_t>(rank) - 1);
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
}

Bitmap falseColour(const ErrorMap &map, double maxValue) {
    // An inferno-like scale (black, purple, red, orange, pale yellow) in sRGB at nine evenly spaced
    // stops: monotonic in lightness, so the order of errors reads the same in grey.
    static constexpr std::array<std::array<double, 3>, 9> kStops = {{{0.0015, 0.0005, 0.0139},
                                                                     {0.0874, 0.0446, 0.2248},
                                                                     {0.2582, 0.0386, 0.4065},
                                                                     {0.4163, 0.0902, 0.4329},
                                                                     {0.5783, 0.1480, 0.4044},
                                                                     {0.7357, 0.2159, 0.3302},
                                                                     {0.8650, 0.3168, 0.2261},
                                                                     {0.9545, 0.4687, 0.0999},
                                                                     {0.9884, 0.9984, 0.6449}}};
    const auto toLinear = [](double s) { return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4); };
    Bitmap out(map.width, map.height);
    const double scale = maxValue > 0 && std::isfinite(maxValue) ? 1.0 / maxValue : 0.0;
    for (size_t p = 0; p < map.values.size(); ++p) {
        const double t = std::clamp(map.values[p] * scale, 0.0, 1.0) * (kStops.size() - 1);
        const size_t i = std::min(static_cast<size_t>(t), kStops.size() - 2);
        const double f = t - static_cast<double>(i);
        for (size_t c = 0; c < 3; ++c)
            out.rgb[3 * p + c] = static_cast<float>(toLinear((1 - f) * kStops[i][c] + f * kStops[i + 1][c]));
    }
    return out;
}

Bitmap blockMeans(const Bitmap &image, int b) {
    if (b < 1) throw MetricError("block size " + std::to_string(b) + " must be positive");
    Bitmap means(image.width / b, image.height / b);
    for (int by = 0; by < means.height; ++by)
        for (int bx = 0; bx < means.width; ++bx) {
            Spectrum sum(0.0);
            for (int y = by * b; y < (by + 1) * b; ++y)
                for (int x = bx * b; x < (bx + 1) * b; ++x) sum += image.get(x, y);
            means.set(bx, by, sum / (b * b));
        }
    return means;
}

}  // namespace pf
