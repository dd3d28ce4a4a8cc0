// The fixed sequence of image task sizes (render/image_task.h) that the embedded renderer and the farm share:
// it depends on the film and the first sample alone (so a time budget takes a prefix of what an spp budget
// takes), it fills an spp budget exactly, and its bounds are in pixel samples, so that the first tasks of a
// large film are short enough for a time budget (at 1024² BDPT, the old first task of 8 spp took 45 s on two
// cores) and no task holds more pixel samples than 256 spp of a 256² film. Also the passes of an embedded
// render under a time budget (timedPassSize), which the clock sizes, and its partial last pass
// (timedPartialTiles).
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "render/image_task.h"

namespace pf::test {
namespace {

constexpr int64_t kOpen = std::numeric_limits<int64_t>::max();  // a time budget's unbounded sequence

// The sizes of the first `count` tasks of an unbounded budget.
std::vector<int64_t> sequence(int64_t pixels, int count) {
    std::vector<int64_t> sizes;
    for (int64_t first = 0; static_cast<int>(sizes.size()) < count; first += sizes.back())
        sizes.push_back(imageTaskSize(kOpen, first, pixels));
    return sizes;
}

TEST(ImageTaskSizes, SmallFilmsStartAtEightAndGrowToTwoHundredFiftySix) {
    for (const int64_t res : {1, 32, 128, 256}) {
        const std::vector<int64_t> sizes = sequence(res * res, 60);
        // 16 tasks of 8 up to sample 128, then each the largest power of two up to 1/8 of the samples before it.
        for (int i = 0; i < 16; ++i) EXPECT_EQ(sizes[i], 8) << res << " task " << i;
        EXPECT_EQ(sizes[16], 16) << res;
        EXPECT_EQ(sizes.back(), 256) << res;
    }
}

TEST(ImageTaskSizes, LargeFilmsScaleBothBoundsByTheirPixels) {
    struct Case {
        int64_t width, height, smallest, largest;
    };
    for (const Case &c : {Case{320, 320, 4, 128}, Case{512, 512, 2, 64}, Case{1024, 1024, 1, 16},
                          Case{1920, 1080, 1, 8}, Case{4096, 4096, 1, 1}}) {
        const int64_t pixels = c.width * c.height;
        const std::vector<int64_t> sizes = sequence(pixels, 200);
        EXPECT_EQ(sizes.front(), c.smallest) << c.width << "x" << c.height;
        EXPECT_EQ(sizes.back(), c.largest) << c.width << "x" << c.height;
        for (size_t i = 0; i < sizes.size(); ++i) {
            if (i > 0) {
                EXPECT_GE(sizes[i], sizes[i - 1]) << "sizes never shrink, task " << i;
            }
            // A task of more than one sample per pixel holds at most 256 spp of a 256² film.
            if (sizes[i] > 1) {
                EXPECT_LE(sizes[i] * pixels, 256 * 256 * 256) << c.width << " task " << i;
            }
        }
    }
}

TEST(ImageTaskSizes, AnySppBudgetIsAPrefixOfTheOpenSequenceCutAtItsEnd) {
    for (const int64_t pixels : {int64_t{48 * 48}, int64_t{700 * 500}, int64_t{1024 * 1024}}) {
        for (const int64_t spp : {1, 7, 40, 129, 1000, 5000}) {
            int64_t first = 0;
            while (first < spp) {
                const int64_t size = imageTaskSize(spp, first, pixels);
                ASSERT_GT(size, 0);
                // Only the last task is cut short by the budget.
                if (first + size < spp) {
                    EXPECT_EQ(size, imageTaskSize(kOpen, first, pixels)) << spp;
                }
                first += size;
            }
            EXPECT_EQ(first, spp) << pixels << " px, " << spp << " spp";
        }
    }
}

// An embedded render under a time budget, on a simulated clock: each pass costs `overhead` seconds plus
// `perSample` per sample per pixel. Returns the passes' sizes; `spent` is the clock at the end.
std::vector<int64_t> timedPasses(double budget, double perSample, double overhead, double &spent) {
    std::vector<int64_t> sizes;
    ImageTask last{0, 0};
    double lastSeconds = 0;
    spent = 0;
    for (int64_t size; (size = timedPassSize(budget, spent, last, lastSeconds)) > 0;) {
        last = ImageTask{last.firstSample + last.sampleCount, size};
        lastSeconds = overhead + perSample * static_cast<double>(size);
        spent += lastSeconds;
        sizes.push_back(size);
    }
    return sizes;
}

TEST(TimedPassSizes, PassesGrowToAFractionOfTheBudgetAndTheLastFillsIt) {
    // 64² path tracing on two cores: about 5 ms per sample per pixel, 0.1 ms per pass of fixed costs.
    double spent = 0;
    const std::vector<int64_t> sizes = timedPasses(10.0, 5e-3, 1e-4, spent);
    ASSERT_FALSE(sizes.empty());
    EXPECT_EQ(sizes.front(), 1);
    for (size_t i = 1; i < sizes.size(); ++i) EXPECT_LE(sizes[i], 2 * sizes[i - 1]) << "pass " << i;
    // Passes of about 10 s / 64 (31 spp), a few to grow there, and a last one that fills what is left.
    EXPECT_EQ(*std::max_element(sizes.begin(), sizes.end()), 31);
    EXPECT_LE(sizes.size(), 64u + 8u);
    EXPECT_LE(spent, 10.0);
    // What is left is less than one more sample per pixel would take (the estimate includes the overhead).
    EXPECT_LT(10.0 - spent, 2 * (5e-3 + 1e-4));
    // One pass per sample per pixel spent about 2000 x 0.1 ms of the 10 s on fixed costs (1960 samples); these
    // passes are fewer than 100.
    int64_t samples = 0;
    for (const int64_t s : sizes) samples += s;
    EXPECT_GE(samples, static_cast<int64_t>((10.0 - 100 * 1e-4) / 5e-3) - 1);
}

TEST(TimedPassSizes, ASlowFilmTakesOneSamplePerPixelPerPassAndStopsBeforeOverrunning) {
    // 1024² BDPT on two cores: 6 s per sample per pixel against a 30 s budget.
    double spent = 0;
    const std::vector<int64_t> sizes = timedPasses(30.0, 6.0, 0.0, spent);
    EXPECT_EQ(sizes, std::vector<int64_t>(5, 1));
    EXPECT_DOUBLE_EQ(spent, 30.0);
    // A first pass longer than the budget is still taken (an image needs one sample), and nothing after it.
    EXPECT_EQ(timedPasses(30.0, 45.0, 0.0, spent), std::vector<int64_t>{1});
}

// When the next whole sample per pixel does not fit, the tiles of one that do, at the last pass's pace: at
// 1024² BDPT (1024 tiles, 5 s per sample per pixel) after five passes in 25.8 s of 30, 860 of them.
TEST(TimedPassSizes, APartialPassTakesTheTilesThatFit) {
    const ImageTask last{4, 1};
    EXPECT_EQ(timedPartialTiles(30.0, 25.8, last, 5.0, 1024), 860);
    // Never the whole film (that would be a whole pass), none when not one tile fits or the pace is unknown.
    EXPECT_EQ(timedPartialTiles(30.0, 25.8, last, 1e-3, 1024), 1023);
    EXPECT_EQ(timedPartialTiles(30.0, 29.999, last, 5.0, 1024), 0);
    EXPECT_EQ(timedPartialTiles(30.0, 31.0, last, 5.0, 1024), 0);
    EXPECT_EQ(timedPartialTiles(30.0, 25.8, ImageTask{0, 0}, 5.0, 1024), 0);
    EXPECT_EQ(timedPartialTiles(30.0, 25.8, last, 0.0, 1024), 0);
    // A pass of several samples per pixel: the pace is per sample.
    EXPECT_EQ(timedPartialTiles(30.0, 29.75, ImageTask{16, 8}, 4.0, 64), 32);
}

// With the last pass's tile times, the first tiles cost their share of it: 4 tiles of a 4 s pass, the first two
// twice as costly as the others (4/6 of the pass: 2.67 s together), so 2 s left holds one of them, where the
// average (1 s a tile) would take two; cheap tiles first, the same 2 s holds three. Times that do not match the
// film's tiles, or sum to nothing, fall back to the average.
TEST(TimedPassSizes, APartialPassIsSizedByWhatItsTilesCost) {
    const ImageTask last{4, 1};
    const std::vector<float> costlyFirst = {2, 2, 1, 1}, cheapFirst = {1, 1, 2, 2};
    EXPECT_EQ(timedPartialTiles(30.0, 28.0, last, 4.0, 4), 2);
    EXPECT_EQ(timedPartialTiles(30.0, 28.0, last, 4.0, 4, costlyFirst), 1);
    EXPECT_EQ(timedPartialTiles(30.0, 28.0, last, 4.0, 4, cheapFirst), 2);
    EXPECT_EQ(timedPartialTiles(30.0, 27.5, last, 4.0, 4, cheapFirst), 2);  // 2.5 s: not the third (2.67 s)
    EXPECT_EQ(timedPartialTiles(30.0, 27.0, last, 4.0, 4, cheapFirst), 3);  // 3 s: the first three, never all four
    EXPECT_EQ(timedPartialTiles(30.0, 26.0, last, 4.0, 4, cheapFirst), 3);
    EXPECT_EQ(timedPartialTiles(30.0, 29.5, last, 4.0, 4, costlyFirst), 0);  // 0.5 s: not even the first (1.33 s)
    EXPECT_EQ(timedPartialTiles(30.0, 28.0, last, 4.0, 4, std::vector<float>{1, 1}), 2);
    EXPECT_EQ(timedPartialTiles(30.0, 28.0, last, 4.0, 4, std::vector<float>(4, 0.0f)), 2);
}

}  // namespace
}  // namespace pf::test
