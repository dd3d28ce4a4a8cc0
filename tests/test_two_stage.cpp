// Two-stage MLT (render/two_stage.h; Mitsuba 0.6's twoStage): the first stage's cells and floor, the
// re-weighting of the seeding pool for the target L / I (b̂', the luminance per depth and the resampling),
// a seeding pool that the first stage leaves untouched, and convergence: pssmlt, mmlt and mlt with two
// stages agree with the same integrators with one stage (block means with standard errors from
// independent seeds), under --spp and under --time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/normalizer.h"
#include "render/two_stage.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

TEST(FirstStage, CellsCoverTheCropWindow) {
    auto scene = loadChainTestScene("cornell-box", 8);
    scene->resizeFilm(20, 12);
    const FirstStageImage image = FirstStageImage::zero(scene->sensor().film(), 8);
    EXPECT_EQ(image.width, 3);
    EXPECT_EQ(image.height, 2);
    EXPECT_EQ(image.luminance.size(), 6u);
    EXPECT_EQ(image.cell({0.0, 0.0}), 0u);
    EXPECT_EQ(image.cell({7.99, 7.99}), 0u);
    EXPECT_EQ(image.cell({8.0, 0.5}), 1u);
    EXPECT_EQ(image.cell({19.5, 11.9}), 5u);
    EXPECT_EQ(image.cell({20.0, 12.0}), 5u) << "the window's far edge stays in the last cell";
    EXPECT_EQ(image.cell({-0.5, 3.0}), 0u);
    EXPECT_FALSE(FirstStageImage{}.enabled());
    EXPECT_EQ(FirstStageImage{}.targetFactor({3.0, 3.0}), 1.0);
}

TEST(FirstStage, ImportanceIsFlooredAtAFractionOfTheMean) {
    FirstStageImage sums;
    sums.reduction = 4;
    sums.width = 3;
    sums.height = 1;
    sums.luminance = {0.0, 1.0, 3.0};
    const FirstStageImage i = firstStageImportance(sums);
    EXPECT_DOUBLE_EQ(i.luminance[0], kFirstStageFloor * 4.0 / 3.0);
    EXPECT_EQ(i.luminance[1], 1.0);
    EXPECT_EQ(i.luminance[2], 3.0);
    EXPECT_DOUBLE_EQ(i.targetFactor({5.0, 0.0}), 1.0);
    sums.luminance = {0.0, 0.0, 0.0};
    EXPECT_EQ(firstStageImportance(sums).luminance, (std::vector<double>{1.0, 1.0, 1.0}))
        << "a first stage that saw nothing leaves one-stage MLT";
}

TEST(FirstStage, TheNormalizerReweightsThePoolForTheSecondStage) {
    // Two seeding results whose first stages sum to I = (2, 4); candidates in both cells and of two depths.
    const auto result = [](std::vector<SeedCandidate> candidates, std::vector<double> firstStage) {
        SeedingResult r;
        r.candidates = std::move(candidates);
        for (const SeedCandidate &c : r.candidates) {
            const size_t d = static_cast<size_t>(c.record.s + c.record.t - 1);
            if (r.depthLuminance.size() <= d) r.depthLuminance.resize(d + 1, 0.0);
            r.depthLuminance[d] += c.weight;
        }
        r.firstStage.reduction = 2;
        r.firstStage.width = 2;
        r.firstStage.height = 1;
        r.firstStage.luminance = std::move(firstStage);
        return r;
    };
    std::vector<SeedingResult> results;
    results.push_back(result({{{0, 0, 0, 3}, 1.0, 0}, {{0, 1, 1, 2}, 2.0, 1}}, {1.5, 1.0}));
    results.push_back(result({{{1, 0, 2, 2}, 4.0, 1}, {{1, 1, 0, 4}, 0.5, 0}}, {0.5, 3.0}));
    const Normalizer n(std::move(results));
    ASSERT_TRUE(n.firstStage().enabled());
    EXPECT_EQ(n.firstStage().luminance, (std::vector<double>{2.0, 4.0}));
    const std::vector<double> expected{1.0 / 2, 2.0 / 4, 4.0 / 4, 0.5 / 2};
    ASSERT_EQ(n.candidates().size(), 4u);
    for (size_t i = 0; i < 4; ++i) EXPECT_DOUBLE_EQ(n.candidates()[i].weight, expected[i]);
    // Depths s + t - 1: 2, 2, 3, 3.
    ASSERT_EQ(n.depthLuminance().size(), 4u);
    EXPECT_DOUBLE_EQ(n.depthLuminance()[2], 1.0);
    EXPECT_DOUBLE_EQ(n.depthLuminance()[3], 1.25);
    EXPECT_DOUBLE_EQ(n.luminance(), 2.25);
    // Systematic resampling of 900 starts gives each candidate K w' / W' of them, up to one.
    std::vector<int> counts(4, 0);
    for (const ChainSeed &s : n.resample(5, 0, 900))
        for (size_t i = 0; i < 4; ++i)
            if (s.record.pixel == n.candidates()[i].record.pixel &&
                s.record.sampleIndex == n.candidates()[i].record.sampleIndex)
                ++counts[i];
    for (size_t i = 0; i < 4; ++i) EXPECT_NEAR(counts[i], 900 * expected[i] / 2.25, 1.0) << i;
}

TEST(FirstStage, SeedingKeepsItsPoolAndAddsAnIndependentImage) {
    auto scene = loadChainTestScene("cornell-box", 32);
    const auto one = makeTestIntegrator(*scene, "pssmlt", {{"luminanceSamples", "4096"}});
    const auto two = makeTestIntegrator(
        *scene, "pssmlt", {{"luminanceSamples", "4096"}, {"twoStage", "true"}, {"firstStageSizeReduction", "8"}});
    const auto &a = dynamic_cast<const ChainIntegrator &>(*one), &b = dynamic_cast<const ChainIntegrator &>(*two);
    // 32 x 32 pixels: 4 seeding tasks of 256 pixels (render/seeding.cpp); each is compared on its own, and
    // their sums make the image's.
    const std::vector<SeedingTask> tasks = a.seedingTasks(*scene);
    ASSERT_EQ(tasks.size(), 4u);
    double stage = 0, pool = 0;
    for (const SeedingTask &task : tasks) {
        const SeedingResult r1 = a.runSeeding(*scene, 0, 11, task), r2 = b.runSeeding(*scene, 0, 11, task);
        EXPECT_FALSE(r1.firstStage.enabled());
        ASSERT_TRUE(r2.firstStage.enabled());
        EXPECT_EQ(r2.firstStage.width, 4);
        EXPECT_EQ(r2.firstStage.height, 4);
        // The same candidates, each with the cell its strategy lands in.
        ASSERT_EQ(r1.candidates.size(), r2.candidates.size());
        for (size_t i = 0; i < r1.candidates.size(); ++i) {
            EXPECT_EQ(r1.candidates[i].record.pixel, r2.candidates[i].record.pixel);
            EXPECT_EQ(r1.candidates[i].weight, r2.candidates[i].weight);
            EXPECT_LT(r2.candidates[i].cell, 16u);
        }
        EXPECT_EQ(r1.depthLuminance, r2.depthLuminance);
        for (double l : r2.firstStage.luminance) stage += l * 64;
        for (double l : r2.depthLuminance) pool += l;
    }
    // The first stage estimates the same image from other samples: its mean luminance per pixel is b̂ per
    // pixel up to noise, and not the same bits.
    EXPECT_NE(stage, pool);
    EXPECT_NEAR(stage / pool, 1.0, 0.1);
}

// The median and the largest relative standard error of the block means (blocks holding at least 1% of the
// image's mean): two stages should lower the largest, which sits in dark blocks.
std::pair<double, double> relativeErrors(const BlockStats &b) {
    std::vector<double> r;
    for (size_t i = 0; i + 1 < b.mean.size(); ++i)
        if (b.mean[i] > 0.01 * b.mean.back()) r.push_back(b.stderr_[i] / b.mean[i]);
    std::sort(r.begin(), r.end());
    return {r[r.size() / 2], r.back()};
}

void printErrors(const std::string &what, const BlockStats &one, const BlockStats &two) {
    const auto [m1, x1] = relativeErrors(one);
    const auto [m2, x2] = relativeErrors(two);
    std::printf("%s: block relative standard error, one stage median %.4f max %.4f; two stages median %.4f max %.4f\n",
                what.c_str(), m1, x1, m2, x2);
}

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene << " " << c.integrator; }
    std::string scene, integrator;
    int mutationsPerPixel;
};

class TwoStageConvergence : public ::testing::TestWithParam<Case> {};

// Block means of two-stage renders agree with those of one-stage renders of other seeds. 16 x 16 blocks
// of a 32 x 32 image, first-stage cells of 8 x 8 pixels, every path left to the chains.
TEST_P(TwoStageConvergence, AgreesWithOneStage) {
    const Case &c = GetParam();
    constexpr int kRes = 32, kBlock = 16, kSeeds = 12;
    auto scene = loadChainTestScene(c.scene, kRes);
    const std::vector<std::pair<std::string, std::string>> params{
        {"directSamples", "-1"}, {"luminanceSamples", std::to_string(kRes * kRes * 4)}};
    auto twoStage = params;
    twoStage.push_back({"twoStage", "true"});
    twoStage.push_back({"firstStageSizeReduction", "8"});
    const BlockStats one =
        blockStats(*scene, *makeTestIntegrator(*scene, c.integrator, params), kBlock, kSeeds, c.mutationsPerPixel, 1);
    const BlockStats two =
        blockStats(*scene, *makeTestIntegrator(*scene, c.integrator, twoStage), kBlock, kSeeds, c.mutationsPerPixel, 2);
    // 13 comparisons per case at 4.5 standard errors of a Student t with 11 degrees of freedom.
    expectBlocksAgree(one, two, 4.5, 0.05, 0.03, c.scene + " " + c.integrator);
    printErrors(c.scene + " " + c.integrator, one, two);
}

INSTANTIATE_TEST_SUITE_P(Scenes, TwoStageConvergence,
                         ::testing::Values(Case{"veach-mis", "pssmlt", 32}, Case{"veach-mis", "mmlt", 64},
                                           Case{"cornell-box", "mlt", 32}),
                         [](const auto &info) {
                             std::string n = info.param.scene + "_" + info.param.integrator;
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

TEST(TwoStage, TimeBudgetAgreesWithOneStage) {
    constexpr int kRes = 32, kBlock = 16, kSeeds = 12;
    auto scene = loadChainTestScene("veach-mis", kRes);
    const auto one = makeTestIntegrator(*scene, "pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", "4096"}});
    const auto two = makeTestIntegrator(*scene, "pssmlt",
                                        {{"directSamples", "-1"},
                                         {"luminanceSamples", "4096"},
                                         {"twoStage", "true"},
                                         {"firstStageSizeReduction", "8"}});
    const BlockStats a = blockStats(*scene, *one, kBlock, kSeeds, 32, 1);
    const BlockStats b = blockStats(*scene, *two, kBlock, kSeeds, 0, 2, 2, 0.4);
    expectBlocksAgree(a, b, 4.5, 0.05, 0.03, "veach-mis pssmlt --time");
    printErrors("veach-mis pssmlt --spp 32 against --time 0.4", a, b);
}

}  // namespace
}  // namespace pf::test
