// Chi-square tests of the warping functions against their densities, and of the discrete and 2D
// piecewise-constant distributions.
#include <gtest/gtest.h>

#include "core/distribution.h"
#include "core/warp.h"
#include "support/chi2.h"

namespace pf::test {
namespace {

constexpr int kTests = 5;  // sphere tests in this file, for the multiple-test correction

Chi2Options options() {
    Chi2Options o;
    o.testCount = kTests;
    return o;
}

TEST(Warp, UniformSphere) {
    const auto r = chi2Sphere(
        [](PCG32 &rng, Vec3 &d) {
            d = warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()});
            return true;
        },
        [](const Vec3 &) { return warp::squareToUniformSpherePdf(); }, options());
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 1e-3);
}

TEST(Warp, UniformHemisphere) {
    const auto r = chi2Sphere(
        [](PCG32 &rng, Vec3 &d) {
            d = warp::squareToUniformHemisphere({rng.nextDouble(), rng.nextDouble()});
            return true;
        },
        [](const Vec3 &v) { return warp::squareToUniformHemispherePdf(v); }, options());
    EXPECT_TRUE(r.passed) << r.report;
}

TEST(Warp, CosineHemisphere) {
    const auto r = chi2Sphere(
        [](PCG32 &rng, Vec3 &d) {
            d = warp::squareToCosineHemisphere({rng.nextDouble(), rng.nextDouble()});
            return true;
        },
        [](const Vec3 &v) { return warp::squareToCosineHemispherePdf(v); }, options());
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 1e-3);
}

TEST(Warp, UniformCone) {
    // The rim lies on a bin boundary (cos theta bins are 0.2 wide), so the quadrature sees no jump
    // inside a bin.
    const double cosCutoff = 0.6;
    const Chi2Options opt = options();
    const auto r = chi2Sphere(
        [&](PCG32 &rng, Vec3 &d) {
            d = warp::squareToUniformCone({rng.nextDouble(), rng.nextDouble()}, cosCutoff);
            return true;
        },
        [&](const Vec3 &v) { return warp::squareToUniformConePdf(v, cosCutoff); }, opt);
    EXPECT_TRUE(r.passed) << r.report;
}

// A deliberately wrong pdf must be detected: guards against a harness that always passes.
TEST(Warp, HarnessRejectsWrongPdf) {
    const auto r = chi2Sphere(
        [](PCG32 &rng, Vec3 &d) {
            d = warp::squareToCosineHemisphere({rng.nextDouble(), rng.nextDouble()});
            return true;
        },
        [](const Vec3 &v) { return warp::squareToUniformHemispherePdf(v); }, options());
    EXPECT_FALSE(r.passed) << r.report;
}

TEST(Warp, UniformDiskAndTriangle) {
    PCG32 rng(3, 4);
    // Disk: the fraction inside radius 0.5 is 1/4; triangle barycentrics stay in the simplex with mean 1/3.
    const int n = 200000;
    int inner = 0;
    double b1 = 0, b2 = 0;
    for (int i = 0; i < n; ++i) {
        const Vec2 p = warp::squareToUniformDiskConcentric({rng.nextDouble(), rng.nextDouble()});
        ASSERT_LE(p.x * p.x + p.y * p.y, 1.0 + 1e-12);
        inner += (p.x * p.x + p.y * p.y < 0.25);
        const Vec2 b = warp::squareToUniformTriangle({rng.nextDouble(), rng.nextDouble()});
        ASSERT_GE(b.x, 0);
        ASSERT_GE(b.y, 0);
        ASSERT_LE(b.x + b.y, 1.0 + 1e-12);
        b1 += b.x;
        b2 += b.y;
    }
    const double p = 0.25, sd = std::sqrt(p * (1 - p) / n);
    EXPECT_NEAR(static_cast<double>(inner) / n, p, 4 * sd);
    // Var of a barycentric coordinate under uniform sampling is 1/18.
    const double sdMean = std::sqrt(1.0 / 18.0 / n);
    EXPECT_NEAR(b1 / n, 1.0 / 3.0, 4 * sdMean);
    EXPECT_NEAR(b2 / n, 1.0 / 3.0, 4 * sdMean);
}

TEST(Distribution, DiscreteFrequenciesMatchWeights) {
    const std::vector<double> w = {1, 0, 3, 0.5, 5.5};
    Distribution1D d(w);
    PCG32 rng(5, 6);
    std::vector<double> obs(w.size(), 0), exp(w.size(), 0);
    const int n = 100000;
    for (int i = 0; i < n; ++i) obs[d.sampleDiscrete(rng.nextDouble())] += 1;
    for (size_t i = 0; i < w.size(); ++i) exp[i] = d.pmf(i) * n;
    const auto r = chi2Histogram(obs, exp, 0.01);
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_EQ(obs[1], 0);
    EXPECT_EQ(obs[3] > 0, true);
}

TEST(Distribution, TwoDimensionalPdfMatchesSamples) {
    const size_t nu = 8, nv = 4;
    std::vector<double> w(nu * nv);
    for (size_t i = 0; i < w.size(); ++i) w[i] = 1.0 + static_cast<double>((i * 7) % 5);
    w[3] = 0;
    Distribution2D d(w, nu, nv);
    PCG32 rng(7, 8);
    const int n = 200000;
    std::vector<double> obs(nu * nv, 0), exp(nu * nv, 0);
    for (int i = 0; i < n; ++i) {
        double pdf;
        const Vec2 p = d.sample({rng.nextDouble(), rng.nextDouble()}, &pdf);
        ASSERT_NEAR(pdf, d.pdf(p), 1e-9 * pdf);
        obs[std::min<size_t>(nv - 1, p.y * nv) * nu + std::min<size_t>(nu - 1, p.x * nu)] += 1;
    }
    for (size_t v = 0; v < nv; ++v)
        for (size_t u = 0; u < nu; ++u) exp[v * nu + u] = d.pdf({(u + 0.5) / nu, (v + 0.5) / nv}) / (nu * nv) * n;
    const auto r = chi2Histogram(obs, exp, 0.01);
    EXPECT_TRUE(r.passed) << r.report;
}

}  // namespace
}  // namespace pf::test
