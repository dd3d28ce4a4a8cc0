// Chi-square goodness-of-fit tests of sampling routines against their densities, in the manner of
// Mitsuba's and pbrt's test suites: draw many samples, histogram them in (cos theta, phi) bins, integrate
// the claimed pdf over each bin numerically, pool bins with small expected counts, and compute the
// p-value of Pearson's statistic. A test fails when p < significance / testCount (Sidak-style
// correction for running many tests).
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "core/rng.h"
#include "core/vector.h"

namespace pf::test {

struct Chi2Options {
    int thetaBins = 10;         // bins in cos(theta) over [-1, 1]
    int phiBins = 20;           // bins in phi over [0, 2 pi)
    int sampleCount = 200000;
    int integrationRes = 6;     // Simpson sub-intervals per bin and dimension (even)
    double significance = 0.01;
    int testCount = 1;          // number of tests run in the suite (for the multiple-test correction)
    uint64_t seed = 1;
};

struct Chi2Result {
    bool passed = false;
    double pValue = 0;
    double statistic = 0;
    int dof = 0;
    double sampledMass = 0;   // fraction of draws that produced a (non-delta) sample
    double integratedMass = 0;  // integral of the pdf over the sphere
    std::string report;       // human-readable summary for test failure messages
};

// Draws one direction; returns false if no (smooth) direction was produced for this draw.
using DirectionSampler = std::function<bool(PCG32 &rng, Vec3 &dir)>;
using DirectionPdf = std::function<double(const Vec3 &dir)>;

Chi2Result chi2Sphere(const DirectionSampler &sample, const DirectionPdf &pdf, const Chi2Options &opt = {});

// Pearson's test on arbitrary histograms (observed vs. expected counts), pooling cells with expected
// count < 5 into one cell; dof = cells - 1.
Chi2Result chi2Histogram(const std::vector<double> &observed, const std::vector<double> &expected,
                         double significance, int testCount = 1);

// Upper regularized incomplete gamma Q(a, x); the chi-square survival function is Q(dof/2, x/2).
double gammaQ(double a, double x);

}  // namespace pf::test
