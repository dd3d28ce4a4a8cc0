// The von Mises-Fisher kernel and the glossy classification of manifold exploration (ALGORITHMS.md §6.8,
// §6.6, §9.2's golden checks): sampling against the density by chi-square for kappa from 0.1 to 1e5,
// sample means against coth kappa - 1/kappa, the peak-density fit, the HG median and the printed-form
// classification example.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/frame.h"
#include "core/warp.h"
#include "manifold/roughness.h"
#include "manifold/vmf.h"
#include "support/chi2.h"

namespace pf::test {
namespace {

const std::vector<double> kKappas = {0.1, 1.0, 10.0, 100.0, 1e3, 1e4, 1e5};

// A mean direction away from the axes, so that the frame rotation is exercised.
Vec3 someMean(PCG32 &rng) { return warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()}); }

// Chi-square of samples around a random mean against eval(), in the lobe's own coordinates: u = 1 - mu.w
// in bins of equal expected mass (the lobe's width is 1 / kappa in u, far below a fixed (cos theta, phi)
// grid at kappa = 1e5) and the azimuth in equal bins. Expected counts integrate eval(mu, w) over each bin
// with Simpson's rule, d(solid angle) = du dphi, at directions w built in the world frame. The u integral
// runs over q = the mass fraction below u, u(q) = -ln(1 - (1 - e^{-2 kappa}) q) / kappa, which a correct
// density makes a constant integrand, so Simpson's rule is exact there and any error of eval() shows.
Chi2Result chi2Lobe(double kappa, int testCount) {
    constexpr int kUBins = 24, kPhiBins = 8, kSamples = 200000, kSimpson = 16;
    const VonMisesFisher vmf(kappa);
    PCG32 rng(7, static_cast<uint64_t>(kappa * 1000));
    const Vec3 mu = someMean(rng);
    const Frame frame(mu);
    // Edges at the quantiles of u; the last ends at q = 1 - 1e-12 (the mass beyond is far below one count).
    std::vector<double> edges(kUBins + 1);
    const double total = -std::expm1(-2 * kappa);
    const auto quantile = [&](double q) { return -std::log1p(-total * q) / kappa; };
    for (int k = 0; k <= kUBins; ++k) edges[k] = quantile(k == kUBins ? 1 - 1e-12 : static_cast<double>(k) / kUBins);
    std::vector<double> observed(kUBins * kPhiBins, 0.0), expected(kUBins * kPhiBins, 0.0);
    for (int s = 0; s < kSamples; ++s) {
        const Vec3 w = vmf.sample(mu, {rng.nextDouble(), rng.nextDouble()});
        const Vec3 local = frame.toLocal(w);
        const double u = (mu - w).lengthSquared() / 2;
        double phi = std::atan2(local.y, local.x);
        if (phi < 0) phi += 2 * kPi;
        const int ub = static_cast<int>(std::upper_bound(edges.begin(), edges.end(), u) - edges.begin()) - 1;
        const int pb = std::min(kPhiBins - 1, static_cast<int>(phi / (2 * kPi) * kPhiBins));
        observed[std::clamp(ub, 0, kUBins - 1) * kPhiBins + pb] += 1;
    }
    for (int ub = 0; ub < kUBins; ++ub)
        for (int pb = 0; pb < kPhiBins; ++pb) {
            const double q0 = static_cast<double>(ub) / kUBins;
            const double dq = ((ub + 1 == kUBins ? 1 - 1e-12 : static_cast<double>(ub + 1) / kUBins) - q0) / kSimpson;
            const double p0 = 2 * kPi * pb / kPhiBins, dp = 2 * kPi / kPhiBins / kSimpson;
            double mass = 0;
            for (int i = 0; i <= kSimpson; ++i)
                for (int j = 0; j <= kSimpson; ++j) {
                    const double wi = (i == 0 || i == kSimpson) ? 1 : (i % 2 ? 4 : 2);
                    const double wj = (j == 0 || j == kSimpson) ? 1 : (j % 2 ? 4 : 2);
                    const double q = q0 + i * dq, u = quantile(q), phi = p0 + j * dp;
                    const double dudq = total / (kappa * (1 - total * q));
                    const double sinTheta = std::sqrt(std::max(0.0, u * (2 - u)));
                    const Vec3 w =
                        normalize(frame.toWorld(Vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), 1 - u)));
                    mass += wi * wj * vmf.eval(mu, w) * dudq;
                }
            expected[ub * kPhiBins + pb] = mass * dq * dp / 9 * kSamples;
        }
    return chi2Histogram(observed, expected, 0.01, testCount);
}

TEST(VonMisesFisher, SamplingMatchesDensityChi2) {
    for (const double kappa : kKappas) {
        const Chi2Result r = chi2Lobe(kappa, static_cast<int>(kKappas.size()));
        EXPECT_TRUE(r.passed) << "kappa " << kappa << ": " << r.report;
    }
}

// The shared (cos theta, phi) harness, where its grid resolves the lobe.
TEST(VonMisesFisher, SamplingMatchesDensitySphereGrid) {
    for (const double kappa : {0.1, 1.0, 10.0}) {
        PCG32 meanRng(3, 5);
        const Vec3 mu = someMean(meanRng);
        const VonMisesFisher vmf(kappa);
        Chi2Options o;
        o.testCount = 3;
        const auto r = chi2Sphere(
            [&](PCG32 &rng, Vec3 &d) {
                d = vmf.sample(mu, {rng.nextDouble(), rng.nextDouble()});
                return true;
            },
            [&](const Vec3 &d) { return vmf.eval(mu, d); }, o);
        EXPECT_TRUE(r.passed) << "kappa " << kappa << ": " << r.report;
        EXPECT_NEAR(r.integratedMass, 1.0, 2e-3) << "kappa " << kappa;
    }
}

TEST(VonMisesFisher, SampleMeansMatchLangevin) {
    constexpr int kSamples = 400000;
    for (const double kappa : kKappas) {
        const VonMisesFisher vmf(kappa);
        PCG32 rng(11, static_cast<uint64_t>(kappa * 10));
        const Vec3 mu = someMean(rng);
        // Moments of u = 1 - mu.w, which keeps its digits at large kappa.
        double sum = 0, sum2 = 0;
        for (int s = 0; s < kSamples; ++s) {
            const double u = (mu - vmf.sample(mu, {rng.nextDouble(), rng.nextDouble()})).lengthSquared() / 2;
            sum += u;
            sum2 += u * u;
        }
        const double mean = sum / kSamples, sigma = std::sqrt((sum2 / kSamples - mean * mean) / kSamples);
        const double expected = 1 - VonMisesFisher::meanCosine(kappa);
        EXPECT_NEAR(mean, expected, 4.5 * sigma) << "kappa " << kappa;
        EXPECT_GT(sigma, 0) << "kappa " << kappa;
    }
}

TEST(VonMisesFisher, MeanCosineSeriesJoinsClosedForm) {
    // coth k - 1/k by long double at a point where both branches are accurate, and the series' limit.
    for (const double k : {1e-3, 9.99e-3, 1.001e-2, 0.5, 3.0}) {
        const long double kl = k, exact = std::cosh(kl) / std::sinh(kl) - 1 / kl;
        EXPECT_NEAR(VonMisesFisher::meanCosine(k), static_cast<double>(exact), 1e-12 * std::max(1.0, k));
    }
    EXPECT_NEAR(VonMisesFisher::meanCosine(1e9), 1 - 1e-9, 1e-15);
}

TEST(VonMisesFisher, EvalIsStableAndNormalized) {
    // No overflow where sinh does (kappa = 1e9), and the peak equals peakDensity.
    const Vec3 mu(0, 0, 1);
    for (const double kappa : {0.0, 1e-8, 0.1, 5.0, 800.0, 1e9}) {
        const VonMisesFisher vmf(kappa);
        EXPECT_TRUE(std::isfinite(vmf.eval(mu, mu))) << kappa;
        EXPECT_NEAR(vmf.eval(mu, mu), VonMisesFisher::peakDensity(kappa), 1e-12 * VonMisesFisher::peakDensity(kappa))
            << kappa;
    }
    // Against the textbook form kappa / (4 pi sinh kappa) exp(kappa cos) where the latter is exact.
    const VonMisesFisher vmf(3.0);
    const Vec3 w = normalize(Vec3(0.3, -0.2, 0.5));
    EXPECT_NEAR(vmf.eval(mu, w), 3.0 / (4 * kPi * std::sinh(3.0)) * std::exp(3.0 * w.z), 1e-12);
    // At kappa = 1e9 the lobe is 1 / sqrt(kappa) ~ 3e-5 rad wide: a direction 3e-5 rad away keeps e^{-0.45}.
    const VonMisesFisher sharp(1e9);
    const Vec3 off(std::sin(3e-5), 0, std::cos(3e-5));
    EXPECT_NEAR(sharp.eval(mu, off) / sharp.eval(mu, mu), std::exp(-1e9 * (1 - std::cos(3e-5))), 1e-6);
}

TEST(VonMisesFisher, KappaFromPeakDensity) {
    // The rational fit's absolute error on kappa in (0, 5] ([TH A3]: < 0.007).
    double maxError = 0;
    for (int i = 1; i <= 5000; ++i) {
        const double kappa = 5.0 * i / 5000;
        maxError = std::max(
            maxError, std::abs(VonMisesFisher::fromPeakDensity(VonMisesFisher::peakDensity(kappa)).kappa() - kappa));
    }
    EXPECT_LT(maxError, 0.007);
    EXPECT_GT(maxError, 1e-4);  // it is a fit, not the exact inverse: the test would notice a substitute
    // Above kappa = 5, kappa = 2 pi c to double precision.
    for (const double kappa : {5.5, 50.0, 1e4, 6e8})
        EXPECT_NEAR(VonMisesFisher::fromPeakDensity(VonMisesFisher::peakDensity(kappa)).kappa(), kappa, 1e-3 * kappa);
    // A peak flatter than uniform has no solution and gets the floor.
    EXPECT_DOUBLE_EQ(VonMisesFisher::fromPeakDensity(0.05).kappa(), 1e-5);
}

// The HG cumulative mass of scattering cosines at least cos theta (Simpson over the density in mu).
double hgMassWithin(double g, double cosTheta) {
    constexpr int kN = 20000;
    const auto p = [g](double m) { return (1 - g * g) / (2 * std::pow(1 + g * g - 2 * g * m, 1.5)); };
    const double h = (1 - cosTheta) / kN;
    double sum = p(cosTheta) + p(1);
    for (int i = 1; i < kN; ++i) sum += (i % 2 ? 4 : 2) * p(cosTheta + i * h);
    return sum * h / 3;
}

TEST(GlossyClassification, HenyeyGreensteinMedian) {
    EXPECT_NEAR(std::cos(hgQuantileAngle(0.8)), 0.944, 5e-4);
    EXPECT_NEAR(hgQuantileAngle(0.8) * 180 / kPi, 19.3, 0.05);
    EXPECT_NEAR(std::cos(hgQuantileAngle(0.0)), 0.0, 1e-12);  // isotropic: the median is the equator
    // The formula is the HG median: half of the mass lies within theta_q of the lobe direction.
    for (const double g : {0.3, 0.8, 0.95}) EXPECT_NEAR(hgMassWithin(g, std::cos(hgQuantileAngle(g))), 0.5, 1e-6) << g;
    // Backward lobes: measured from the backward direction, the same angle as for |g|.
    EXPECT_NEAR(hgMassWithin(0.5, std::cos(hgQuantileAngle(-0.5))), 0.5, 1e-6);
}

TEST(GlossyClassification, PrintedFormExample) {
    // [TR A1] printed form: alpha = 0.1, dtheta = 1 degree -> P_nonspec ~ 0.32 (ALGORITHMS.md §6.6).
    const double dtheta = kPi / 180;
    EXPECT_NEAR(beckmannQuantileAngle(0.1), std::atan(0.01 * std::log(10.0)), 1e-15);
    EXPECT_NEAR(nonSpecularProbabilitySurface(0.1, dtheta), 0.32, 0.005);
    EXPECT_NEAR(specularProbability(beckmannQuantileAngle(0.1), dtheta), 0.68, 0.005);
    // The erratum's limits: smooth surfaces are always specular, diffuse ones never.
    EXPECT_EQ(nonSpecularProbabilitySurface(0.0, dtheta), 0.0);
    EXPECT_EQ(nonSpecularProbabilitySurface(INFINITY, dtheta), 1.0);
    // Rougher is less specular.
    EXPECT_LT(nonSpecularProbabilitySurface(0.05, dtheta), nonSpecularProbabilitySurface(0.2, dtheta));
    // theta_q + dtheta is capped at pi: a wide HG lobe with a large step gives a probability below 1.
    EXPECT_NEAR(nonSpecularProbability(3.0, 0.5), (1 - std::cos(3.0)) / 2, 1e-12);
}

}  // namespace
}  // namespace pf::test
