// Error metrics of a rendered image against a reference, as used to compare rendering algorithms at
// equal time (ALGORITHMS.md §8: RMSE/rRMSE against a long reference; issue 8 for the list).
//
// Every metric is the mean over pixels of a per-pixel error, which is the mean over the R, G and B
// channels of a per-channel term, with a = the image's value and b = the reference's value:
//   MSE    (a - b)^2                          RMSE = sqrt(MSE)
//   relMSE (a - b)^2 / (b^2 + eps)            relative MSE
//   MAPE   |a - b| / (|b| + eps)              mean absolute percentage error, as a fraction
//   SMAPE  |a - b| / (|a| + |b| + eps)        symmetric MAPE, in [0, 1)
// eps (MetricOptions::epsilon, 1e-2 by default, the usual choice in the adaptive-rendering literature)
// keeps dark reference pixels from dominating the relative errors; reports state it. The optional trim discards, for
// each metric separately, the floor(trimFraction * pixels) pixels of highest error before averaging: a few fireflies
// otherwise decide the comparison (e.g. 0.001, the highest 0.1%). RMSE is trimmed as MSE is.
#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "image/bitmap.h"

namespace pf {

// Images that cannot be compared: different sizes, empty, or holding NaN or infinite values. The
// message names which image ("image" or "reference") and the pixel.
class MetricError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

enum class Metric { MSE, RMSE, RelMSE, MAPE, SMAPE };

// "mse", "rmse", "relmse", "mape", "smape": the names reports and JSON use.
std::string metricName(Metric m);
// The metric's definition as one line of text, with the epsilon written out where it is used.
std::string metricDefinition(Metric m, double epsilon);
const std::vector<Metric> &allMetrics();

struct MetricOptions {
    double epsilon = 1e-2;      // in the denominators of relMSE, MAPE and SMAPE
    double trimFraction = 0.0;  // in [0, 0.5]: the share of highest per-pixel errors discarded per metric
};

struct ErrorMetrics {
    double mse = 0, rmse = 0, relMse = 0, mape = 0, smape = 0;
    int64_t pixels = 0;         // pixels of the image
    int64_t trimmedPixels = 0;  // of them, discarded from each metric's mean
    MetricOptions options;
    double get(Metric m) const;
};

// Checks that `image` and `reference` can be compared (MetricError otherwise) and computes every
// metric of `image` against `reference`.
ErrorMetrics computeMetrics(const Bitmap &image, const Bitmap &reference, const MetricOptions &options = {});

// The image's means over b x b blocks of pixels, one pixel per block (blocks cut by the right or bottom border are
// left out): errors of block means measure how well a render gets regions right, which per-pixel errors hide.
Bitmap blockMeans(const Bitmap &image, int b);

// Efficiency of a render: 1 / (error x seconds), the Monte Carlo efficiency 1 / (variance x time) of
// Veach's thesis (ch. 2) with a measured error in place of the variance: for an unbiased estimator the
// (squared) error falls as 1/time, so this is comparable across budgets. Infinite for a
// zero error; throws std::invalid_argument for a negative error or a non-positive time.
double efficiency(double error, double seconds);

// A per-pixel error map (the per-pixel error the image metric averages), row-major.
struct ErrorMap {
    int width = 0, height = 0;
    std::vector<double> values;
};
// The per-pixel error of `m` (RMSE maps to the root of the squared error). Checks as computeMetrics.
ErrorMap errorMap(const Bitmap &image, const Bitmap &reference, Metric m, double epsilon = 1e-2);
// The value below which `q` (in [0, 1]) of the map's values lie (nearest rank).
double quantile(const ErrorMap &map, double q);
// A false-colour picture of the map: 0 is black, `maxValue` and above the brightest colour of the
// "inferno" colour scale. The Bitmap holds linear values whose sRGB encoding (writePNG with exposure 0)
// is the colour scale itself.
Bitmap falseColour(const ErrorMap &map, double maxValue);

}  // namespace pf
