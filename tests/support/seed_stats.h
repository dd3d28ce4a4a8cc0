// Mean and standard error of per-block (or per-pixel) estimates over independent seeds, from their sums and
// sums of squares: each seed's image is an independent estimate, so the seed-to-seed spread gives the error
// whatever the correlations between pixels. Shared by the agreement tests' block statistics.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

namespace pf::test {

inline void seedMeanAndError(const std::vector<double> &sum, const std::vector<double> &sum2, int seeds,
                             std::vector<double> &mean, std::vector<double> &stderr_) {
    for (size_t i = 0; i < sum.size(); ++i) {
        const double m = sum[i] / seeds;
        mean.push_back(m);
        stderr_.push_back(std::sqrt(std::max(0.0, sum2[i] / seeds - m * m) / (seeds - 1)));
    }
}

}  // namespace pf::test
