// Discrete and piecewise-constant distributions (pbrt-v3 §13.3.1, §13.6.7), used for light selection,
// triangle selection by area and environment-map importance sampling.
#pragma once
#include <cstddef>
#include <vector>

#include "core/vector.h"

namespace pf {

class Distribution1D {
public:
    Distribution1D() = default;
    explicit Distribution1D(const std::vector<double> &weights);
    size_t size() const { return func_.size(); }
    double sum() const { return sum_; }
    bool empty() const { return sum_ <= 0; }
    // Discrete: returns index with probability w_i / sum; remaps u to [0,1) for reuse.
    size_t sampleDiscrete(double u, double *pmf = nullptr, double *uRemapped = nullptr) const;
    double pmf(size_t i) const { return pmf_[i]; }
    // Continuous on [0,1): piecewise-constant density proportional to the weights.
    double sampleContinuous(double u, double *pdf = nullptr, size_t *offset = nullptr) const;
    double pdfContinuous(double x) const;

private:
    std::vector<double> func_, cdf_;
    std::vector<double> pmf_;  // func_[i] / sum_ (0 without mass), divided once here rather than per sample
    double sum_ = 0;
};

// Piecewise-constant 2D density on [0,1)^2 from a row-major nu x nv grid of weights.
class Distribution2D {
public:
    Distribution2D() = default;
    Distribution2D(const std::vector<double> &weights, size_t nu, size_t nv);
    Vec2 sample(const Vec2 &u, double *pdf) const;
    double pdf(const Vec2 &p) const;

private:
    std::vector<Distribution1D> conditional_;
    Distribution1D marginal_;
    size_t nu_ = 0, nv_ = 0;
};

}  // namespace pf
