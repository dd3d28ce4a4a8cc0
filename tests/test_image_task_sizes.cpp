// The fixed sequence of image task sizes (render/image_task.h) that the embedded renderer and the farm share:
// it depends on the film and the first sample alone (so a time budget takes a prefix of what an spp budget
// takes), it fills an spp budget exactly, and its bounds are in pixel samples, so that the first tasks of a
// large film are short enough for a time budget (at 1024² BDPT, the old first task of 8 spp took 45 s on two
// cores) and no task holds more pixel samples than 256 spp of a 256² film.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pf::test
