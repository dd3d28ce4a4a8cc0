// Seeding and normalization (render/seeding.h, render/normalizer.h; ALGORITHMS.md §2.3-2.4, §5.3, §9.1.5):
// b̂ is the BDPT estimate of the total image luminance, candidates regenerate exactly from their records,
// chain starts are drawn in proportion to weight (chi-square), per-pixel pools add up to the whole, and a
// chain's start state is the candidate it was resampled from.
#include <gtest/gtest.h>

#include <map>

#include "integrators/bdpt.h"
#include "mcmc/pss_integrator.h"
#include "render/normalizer.h"
#include "support/chi2.h"
#include "support/seed_stats.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

constexpr uint64_t kSeed = 4242;

Normalizer seedAll(const Scene &scene, const SeedingConfig &config, uint64_t seed) {
    std::vector<SeedingResult> results;
    for (const SeedingTask &t : seedingTasks(scene)) results.push_back(runSeedingTask(scene, config, seed, t));
    return Normalizer(std::move(results));
}

const PrimarySampleIntegrator &asPSS(const Integrator &i) { return dynamic_cast<const PrimarySampleIntegrator &>(i); }

double imageLuminance(const Bitmap &img) {
    double sum = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x) sum += img.get(x, y).luminance();
    return sum;
}

class Seeding : public ::testing::TestWithParam<std::string> {};

// §2.3: b̂ (the sum of the candidate weights, which carry 1 / spp) equals the total luminance of the
// `bdpt` image rendered with the same seed and samples per pixel (a box filter puts every sample in its own
// pixel), up to the image's float storage. The per-pixel pools add up to the same total (§9.1.5).
TEST_P(Seeding, LuminanceIsTheBDPTEstimateOfTheImageTotal) {
    auto scene = loadChainTestScene(GetParam(), 16);
    const int spp = 8;
    const auto pssmlt = makeTestIntegrator(*scene, "pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", "2048"}});
    const SeedingConfig config = asPSS(*pssmlt).seeding(*scene);
    ASSERT_EQ(config.samplesPerPixel, spp);
    ASSERT_EQ(config.minDepth, 1);
    const Normalizer n = seedAll(*scene, config, kSeed);

    RenderOptions opt;
    opt.spp = spp;
    opt.seed = kSeed;
    opt.threads = 1;
    RenderStats stats;
    const Bitmap bdpt = makeTestIntegrator(*scene, "bdpt", {})->render(*scene, opt, stats);
    const double total = imageLuminance(bdpt);
    ASSERT_GT(total, 0);
    EXPECT_NEAR(n.luminance(), total, 1e-6 * total);

    double weights = 0, depths = 0;
    for (const SeedCandidate &c : n.candidates()) weights += c.weight;
    for (double d : n.depthLuminance()) depths += d;
    EXPECT_NEAR(weights, n.luminance(), 1e-12 * total);
    EXPECT_DOUBLE_EQ(depths, n.luminance());
}

// Every candidate regenerates from (seed, record) with exactly its weight (ARCHITECTURE.md: no paths on
// the wire), and leaving out the direct component drops exactly the paths of at most two edges.
TEST_P(Seeding, CandidatesRegenerateExactly) {
    auto scene = loadChainTestScene(GetParam(), 16);
    const auto all = makeTestIntegrator(*scene, "pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", "1024"}});
    const auto indirect = makeTestIntegrator(*scene, "pssmlt", {{"luminanceSamples", "1024"}});
    const SeedingConfig config = asPSS(*all).seeding(*scene);
    const Normalizer n = seedAll(*scene, config, kSeed), m = seedAll(*scene, asPSS(*indirect).seeding(*scene), kSeed);
    ASSERT_GT(n.candidates().size(), 100u);
    size_t checked = 0;
    for (size_t i = 0; i < n.candidates().size(); i += 7, ++checked) {
        const SeedCandidate &c = n.candidates()[i];
        double again = -1;
        EXPECT_TRUE(config.bdpt->regenerate(*scene, kSeed, c.record, [&](const StrategySample &x) {
            again = x.value.luminance() / static_cast<double>(config.samplesPerPixel);
        }));
        EXPECT_EQ(again, c.weight) << "candidate " << i;
    }
    EXPECT_GT(checked, 10u);
    std::vector<SeedCandidate> deep;
    for (const SeedCandidate &c : n.candidates())
        if (c.record.s + c.record.t - 1 >= 3) deep.push_back(c);
    ASSERT_EQ(deep.size(), m.candidates().size());
    for (size_t i = 0; i < deep.size(); ++i) {
        EXPECT_EQ(deep[i].record.pixel, m.candidates()[i].record.pixel);
        EXPECT_EQ(deep[i].record.sampleIndex, m.candidates()[i].record.sampleIndex);
        EXPECT_EQ(deep[i].weight, m.candidates()[i].weight);
    }
}

// §2.4: long-chain starts are drawn with probability w_i / W (independently per task, stratified within
// one). Pearson's chi-square over the candidates (cells with small expectations pooled).
TEST_P(Seeding, ResamplingIsProportionalToWeight) {
    auto scene = loadChainTestScene(GetParam(), 8);
    const auto pssmlt = makeTestIntegrator(*scene, "pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", "256"}});
    const Normalizer n = seedAll(*scene, asPSS(*pssmlt).seeding(*scene), kSeed);
    const auto &pool = n.candidates();
    ASSERT_GT(pool.size(), 50u);
    const auto indexOf = [&](const PathRecord &r) {
        for (size_t i = 0; i < pool.size(); ++i)
            if (pool[i].record.pixel == r.pixel && pool[i].record.sampleIndex == r.sampleIndex &&
                pool[i].record.s == r.s && pool[i].record.t == r.t)
                return i;
        ADD_FAILURE() << "resampled a record that is not in the pool";
        return size_t(0);
    };
    // One chain per task (independent draws), and ten per task (stratified within the task).
    constexpr int kDraws = 100000;
    std::vector<double> observed(pool.size(), 0.0), expected(pool.size());
    for (size_t i = 0; i < pool.size(); ++i) expected[i] = kDraws * pool[i].weight / n.luminance();
    for (uint64_t perTask : {1, 10}) {
        std::fill(observed.begin(), observed.end(), 0.0);
        for (uint64_t k = 0; k < kDraws / perTask; ++k) {
            const std::vector<ChainSeed> seeds = n.resample(kSeed, k, perTask);
            ASSERT_EQ(seeds.size(), perTask);
            for (const ChainSeed &s : seeds) {
                EXPECT_EQ(s.weight, 1.0);
                observed[indexOf(s.record)] += 1;
            }
        }
        const Chi2Result global = chi2Histogram(observed, expected, 0.01, 3);
        EXPECT_TRUE(global.passed) << perTask << " per task: " << global.report;
    }
}

// A chain starts on its candidate: PSSMLT's target there is the luminance of the candidate's whole BDPT
// sample (all its strategies), MMLT's the candidate's strategy times the d + 2 strategies of its depth.
// (Equal up to the rounding of the raster position into primary-sample coordinates.)
TEST_P(Seeding, ChainsStartOnTheirCandidates) {
    auto scene = loadChainTestScene(GetParam(), 16);
    for (const std::string type : {"pssmlt", "mmlt"}) {
        const auto integrator = makeTestIntegrator(*scene, type, {{"luminanceSamples", "1024"}});
        const PrimarySampleIntegrator &pss = asPSS(*integrator);
        const SeedingConfig config = pss.seeding(*scene);
        const Normalizer n = seedAll(*scene, config, kSeed);
        ChainTask task;
        task.depthLuminance = n.depthLuminance();
        ImageBlock film(0, 0, 16, 16, nullptr);
        for (uint64_t k = 0; k < 40; ++k) {
            const ChainSeed seed = n.resample(kSeed, k, 1)[0];
            double expected = 0;
            for (const SeedCandidate &c : n.candidates())
                if (c.record.pixel == seed.record.pixel && c.record.sampleIndex == seed.record.sampleIndex &&
                    (type == "pssmlt" || (c.record.s == seed.record.s && c.record.t == seed.record.t)))
                    expected +=
                        c.weight * config.samplesPerPixel * (type == "pssmlt" ? 1 : seed.record.s + seed.record.t + 1);
            PCG32 rng(k, 1);
            const auto started = pss.startChain(*scene, kSeed, task, seed, 1.0, rng, film);
            EXPECT_NEAR(started.chain->target(), expected, 1e-9 * expected) << type << " chain " << k;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, Seeding, ::testing::Values("cornell-box", "veach-mis", "veach-bidir"));

// Sparse seeding (luminanceSamples below one per pixel, render/seeding.h): one pixel of each run of
// pixelStride is seeded, weighted by the run's length. At 96² (seeding tasks of 4096, 4096 and 1024 pixels) a
// stride of 7 leaves each task a shorter last run: every run must be seeded exactly once, by one pixel of its
// own task (the master refuses candidates outside a task), and b̂'s mean over seeds must agree with dense
// seeding's (one sample in every pixel). Dropping the length factor would make b̂ 7 times too small; picking a
// pixel other than uniformly would bias it where the image varies.
TEST(SparseSeeding, OnePixelPerRunAndUnbiasedLuminance) {
    constexpr int kRes = 96, kSeeds = 16;
    constexpr uint64_t kPixels = kRes * kRes, kStride = 7;
    auto scene = loadChainTestScene("cornell-box", kRes);
    const auto pssmlt = makeTestIntegrator(
        *scene, "pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(kPixels / kStride)}});
    const SeedingConfig sparse = asPSS(*pssmlt).seeding(*scene);
    ASSERT_EQ(sparse.pixelStride, kStride);
    ASSERT_EQ(sparse.samplesPerPixel, 1);
    SeedingConfig dense = sparse;
    dense.pixelStride = 1;

    uint64_t samples = 0, expected = 0;
    std::map<uint64_t, uint64_t> pixelOfRun;  // the full film is the crop window: record pixel = crop index
    for (const SeedingTask &t : seedingTasks(*scene)) {
        const SeedingResult r = runSeedingTask(*scene, sparse, kSeed, t);
        samples += r.samples;
        for (const SeedCandidate &c : r.candidates) {
            ASSERT_GE(c.record.pixel, t.firstPixel);
            ASSERT_LT(c.record.pixel, t.firstPixel + t.pixelCount);
            const uint64_t run = t.firstPixel + (c.record.pixel - t.firstPixel) / kStride * kStride;
            const auto [it, fresh] = pixelOfRun.emplace(run, c.record.pixel);
            EXPECT_TRUE(fresh || it->second == c.record.pixel) << "run " << it->first << " seeded twice";
        }
        expected += (t.pixelCount + kStride - 1) / kStride;
    }
    EXPECT_EQ(samples, expected);
    EXPECT_GT(pixelOfRun.size(), samples / 4) << "too few runs hold a path to have tested anything";

    std::vector<double> sum(2, 0.0), sum2(2, 0.0), mean, error;
    for (int k = 0; k < kSeeds; ++k)
        for (int d = 0; d < 2; ++d) {
            const double b = seedAll(*scene, d ? dense : sparse, kSeed + 101 * static_cast<uint64_t>(k)).luminance();
            sum[d] += b;
            sum2[d] += b * b;
        }
    seedMeanAndError(sum, sum2, kSeeds, mean, error);
    std::printf("b: sparse %.5g +- %.2g, dense %.5g +- %.2g\n", mean[0], error[0], mean[1], error[1]);
    EXPECT_LT(error[0], 0.05 * mean[0]) << "too noisy to test the weights";
    EXPECT_NEAR(mean[0], mean[1], 4 * std::hypot(error[0], error[1]));
}

}  // namespace
}  // namespace pf::test
