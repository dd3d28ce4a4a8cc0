// The primary sample space (mcmc/primary_sample.h, mcmc/pss_chain.h; Kelemen et al. 2002; ALGORITHMS.md
// §3.2, §9.1.4): the small-step kernel's distribution and support, a lazily extended chain on a toy
// integrand whose dimension depends on the state (exact bin integrals, independent repeated runs), and
// detailed balance of the small and large steps of PSSMLT and MMLT on the shared scenes.
#include <gtest/gtest.h>

#include <cmath>

#include "mcmc/pss_integrator.h"
#include "render/normalizer.h"
#include "support/chi2.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

const MutationSizes kSizes;

// The density of one coordinate's small step from `from` to `to` (Kelemen et al. 2002 §4.1): the offset,
// taken on the circle, has a log-uniform magnitude r in [s1, s2] and a random sign: 1 / (2 r ln(s2 / s1)).
double smallStepDensity(double from, double to) {
    double d = to - from;
    d -= std::round(d);
    const double r = std::abs(d), slack = 1e-12;
    if (r < kSizes.low * (1 - slack) || r > kSizes.high * (1 + slack)) return 0.0;
    return 1.0 / (2 * r * std::log(kSizes.high / kSizes.low));
}

// Offsets are log-uniform in magnitude, equally often positive and negative, and wrap onto [0, 1).
TEST(PrimarySample, SmallStepKernel) {
    constexpr int kBinsPerSign = 20, kDraws = 400000;
    std::vector<double> observed(2 * kBinsPerSign, 0.0), expected(2 * kBinsPerSign, kDraws / (2.0 * kBinsPerSign));
    PCG32 rng(7, 3);
    const double logRange = std::log(kSizes.high / kSizes.low);
    const SmallStep smallStep(kSizes);
    for (int i = 0; i < kDraws; ++i) {
        // Starting points near the ends exercise the wrap.
        const double u = i % 4 == 0   ? rng.nextDouble() * 1e-3
                         : i % 4 == 1 ? 1 - rng.nextDouble() * 1e-3
                                      : rng.nextDouble();
        const double v = smallStep(u, rng);
        ASSERT_GE(v, 0.0);
        ASSERT_LT(v, 1.0);
        ASSERT_GT(smallStepDensity(u, v), 0.0) << u << " -> " << v;
        ASSERT_GT(smallStepDensity(v, u), 0.0) << "asymmetric support: " << u << " -> " << v;
        double d = v - u;
        d -= std::round(d);
        const int bin = std::clamp(static_cast<int>(std::log(std::abs(d) / kSizes.low) / logRange * kBinsPerSign), 0,
                                   kBinsPerSign - 1);
        observed[static_cast<size_t>(bin + (d > 0 ? kBinsPerSign : 0))] += 1;
    }
    const Chi2Result r = chi2Histogram(observed, expected, 0.01);
    EXPECT_TRUE(r.passed) << r.report;
}

// A toy Psi whose dimension depends on the state: u0 < 1/2 reads u1 and splats 3 u1^2 at (u0, u1); else it
// reads u1, u2, u3 and splats (u1 + u2) u3 twice, at (u0, u3) and at (u0, u2). Its total is b = 1. Chains
// start from a pool of 4096 uniform samples resampled by the Normalizer (ALGORITHMS.md §2.4), so
// W / M times the deposits estimate each bin's integral without bias, whatever the chain length.
constexpr int kToyBins = 4;

void toyPsi(Sampler &u, SplatList &out) {
    const double u0 = u.next1D(), u1 = u.next1D();
    if (u0 < 0.5) {
        out.push_back({Vec2(u0, u1) * kToyBins, Spectrum(3 * u1 * u1)});
        return;
    }
    const double u2 = u.next1D(), u3 = u.next1D(), g = (u1 + u2) * u3;
    out.push_back({Vec2(u0, u3) * kToyBins, Spectrum(g)});
    out.push_back({Vec2(u0, u2) * kToyBins, Spectrum(g)});
}

double toyBinIntegral(int i, int j) {
    const double w = 1.0 / kToyBins, lo = j * w, hi = lo + w;
    if (i < kToyBins / 2) return w * (hi * hi * hi - lo * lo * lo);
    return w * ((hi * hi - lo * lo) / 2 + 0.5 * (w / 2 + (hi * hi - lo * lo) / 2));
}

TEST(PrimarySample, LazyChainIntegratesAToyWithStateDependentDimension) {
    constexpr int kPool = 4096, kRuns = 48;
    constexpr uint64_t kSteps = 20000, kSeed = 5;
    SeedingResult pool;
    double total = 0;
    for (int i = 0; i < kPool; ++i) {
        IndependentSampler s(kSeed, 0, static_cast<uint64_t>(i));
        SplatList splats;
        toyPsi(s, splats);
        const double w = splatLuminance(splats) / kPool;
        pool.candidates.push_back({{0, static_cast<uint64_t>(i), 0, 0}, w});
        total += w;
    }
    pool.depthLuminance = {total};
    const Normalizer normalizer({pool});
    for (bool kelemen : {true, false}) {
        std::vector<double> sum(kToyBins * kToyBins, 0.0), sum2(sum.size(), 0.0);
        MutationCounts counts = PrimarySampleChain::mutationTypes();
        for (int r = 0; r < kRuns; ++r) {
            ImageBlock film(0, 0, kToyBins, kToyBins, nullptr);
            PrimarySampleChain chain(toyPsi, {0.3, kSizes}, film, 1.0);
            const ChainSeed seed = normalizer.resample(kSeed, static_cast<uint64_t>(r), 1)[0];
            IndependentSampler source(kSeed, 0, seed.record.sampleIndex);
            EXPECT_GT(chain.start({}, source), 0.0);
            PCG32 rng(kSeed + static_cast<uint64_t>(r), 77);
            const KelemenWeights weights{0.3, normalizer.luminance()};
            runMetropolis(chain, kSteps, rng, kelemen ? &weights : nullptr, counts);
            for (int j = 0; j < kToyBins; ++j)
                for (int i = 0; i < kToyBins; ++i) {
                    const double v = film.splatSum(i, j).r * normalizer.luminance() / kSteps;
                    sum[static_cast<size_t>(j * kToyBins + i)] += v;
                    sum2[static_cast<size_t>(j * kToyBins + i)] += v * v;
                }
        }
        for (int j = 0; j < kToyBins; ++j)
            for (int i = 0; i < kToyBins; ++i) {
                const size_t k = static_cast<size_t>(j * kToyBins + i);
                const double mean = sum[k] / kRuns, se = std::sqrt((sum2[k] / kRuns - mean * mean) / (kRuns - 1));
                const double exact = toyBinIntegral(i, j);
                // 1% of the bin's integral plus the average bin's (the darkest bins hold 0.4% of b = 1).
                EXPECT_LT(se, 0.01 * (exact + 1.0 / (kToyBins * kToyBins)))
                    << "bin (" << i << ", " << j << "): too noisy to compare";
                EXPECT_NEAR(mean, exact, 4 * se)
                    << (kelemen ? "Kelemen" : "Veach") << " bin (" << i << ", " << j << ")";
            }
        for (const MutationCount &c : counts) EXPECT_GT(c.accepted, c.proposed / 10) << c.name;
    }
}

// ALGORITHMS.md §9.1.4: for random current states of PSSMLT's and MMLT's chains on the shared scenes and
// proposals drawn by the mutations, pi(x) T(x -> y) a(x -> y) = pi(y) T(y -> x) a(y -> x), with T the
// product of the small-step densities of the coordinates the proposal changed (the large step's T is 1
// both ways), and every move's reverse is possible (symmetric support).
class PrimarySampleDetailedBalance : public ::testing::TestWithParam<std::string> {};

TEST_P(PrimarySampleDetailedBalance, SmallAndLargeSteps) {
    auto scene = loadChainTestScene(GetParam(), 16);
    constexpr uint64_t kSeed = 31;
    for (const std::string type : {"pssmlt", "mmlt"}) {
        const auto integrator =
            makeTestIntegrator(*scene, type, {{"luminanceSamples", "1024"}, {"directSamples", "-1"}});
        const auto &pss = dynamic_cast<const PrimarySampleIntegrator &>(*integrator);
        std::vector<SeedingResult> seeds;
        for (const SeedingTask &t : seedingTasks(*scene))
            seeds.push_back(runSeedingTask(*scene, pss.seeding(*scene), kSeed, t));
        const Normalizer normalizer(std::move(seeds));
        ChainTask task;
        task.depthLuminance = normalizer.depthLuminance();
        ImageBlock film(0, 0, 16, 16, nullptr);
        int checked[2] = {0, 0}, accepted[2] = {0, 0};
        for (uint64_t c = 0; c < 6; ++c) {
            PCG32 rng(kSeed, c);
            const auto started =
                pss.startChain(*scene, kSeed, task, normalizer.resample(kSeed, c, 1)[0], 1.0, rng, film);
            PrimarySampleChain &chain = *started.chain;
            for (int step = 0; step < 150; ++step) {
                const double pix = chain.target();
                ASSERT_GT(pix, 0.0);
                const Proposal p = chain.propose(rng);
                double logTxy = 0, logTyx = 0;
                for (const PrimarySample::Change &ch : chain.primarySample().changes()) {
                    ASSERT_GE(ch.to, 0.0);
                    ASSERT_LT(ch.to, 1.0);
                    if (p.type == PrimarySampleChain::kLargeStep) continue;
                    const double txy = smallStepDensity(ch.from, ch.to), tyx = smallStepDensity(ch.to, ch.from);
                    ASSERT_GT(txy, 0.0) << type << ": coordinate " << ch.index << " moved outside the kernel";
                    ASSERT_GT(tyx, 0.0) << type << ": asymmetric support at coordinate " << ch.index;
                    logTxy += std::log(txy);
                    logTyx += std::log(tyx);
                }
                const double axy = acceptance(pix, p);
                const Proposal reverse{p.type, pix, p.backward, p.forward, p.independent};
                const double ayx = acceptance(p.target, reverse);
                if (p.target > 0) {
                    const double lhs = std::log(pix) + logTxy + std::log(axy),
                                 rhs = std::log(p.target) + logTyx + std::log(ayx);
                    EXPECT_NEAR(lhs, rhs, 1e-9 * (1 + std::abs(lhs))) << type << " step " << step;
                    ++checked[p.type];
                } else {
                    EXPECT_EQ(axy, 0.0);
                }
                if (axy > 0 && rng.nextDouble() < axy) {
                    chain.accept();
                    ++accepted[p.type];
                } else {
                    chain.reject();
                }
            }
        }
        for (int t = 0; t < 2; ++t) {
            EXPECT_GT(checked[t], 20) << type << " type " << t;
            EXPECT_GT(accepted[t], 0) << type << " type " << t;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, PrimarySampleDetailedBalance,
                         ::testing::Values("cornell-box", "veach-mis", "veach-bidir"));

}  // namespace
}  // namespace pf::test
