// A worker's batch of chain tasks (worker/chain_batch.h, issue 17): the results are summed in task order whatever
// order the tasks end in, so that a batch has the same bits however its threads ran; a task without a result
// (it failed, or its lease was lost) ends the run before it and the tasks after it form a new run; and the sum
// of tile films (addChainResult) is what the master's merge of the tasks one by one gives.
#include <gtest/gtest.h>

#include <cstring>

#include "chain_batch.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

using worker::ChainBatch;

class ChainBatchTest : public ::testing::Test {
protected:
    void SetUp() override { scene = loadChainTestScene("cornell-box", 24); }
    // A task's result: a tile film with splats of `value`, and figures of its own.
    ChainResult result(double value) const {
        ChainResult r{makeFilmBlock(*scene, BlockStorage::Tiles),
                      static_cast<uint64_t>(value * 10),
                      static_cast<uint64_t>(value),
                      {{"a", static_cast<uint64_t>(value * 10), static_cast<uint64_t>(value * 5)}},
                      {},
                      static_cast<uint64_t>(value * 100),
                      value};
        // One pixel shared by every task, where the order of the additions shows in the bits.
        r.film.splat(Vec2(1.5, 2.5), Spectrum(value / 3));
        for (int k = 1; k < 3; ++k) r.film.splat(Vec2(1.5 + 7 * k + value, 2.5 + 5 * k), Spectrum(value / 3));
        return r;
    }
    // The dense film of results merged one by one (the master's merge without batches).
    ImageBlock merged(const std::vector<double> &values) const {
        ChainImage image(makeFilmBlock(*scene));
        for (const double v : values) mergeChainResult(image, result(v));
        return std::move(image.film);
    }
    static bool sameSplats(const ImageBlock &a, const ImageBlock &b) {
        return a.splatData().size() == b.splatData().size() &&
               std::memcmp(a.splatData().data(), b.splatData().data(), a.splatData().size_bytes()) == 0;
    }
    std::unique_ptr<Scene> scene;
};

TEST_F(ChainBatchTest, ResultsAreSummedInTaskOrderWhateverOrderTheyEnd) {
    // Added in reverse, the three small values would first sum to a tenth more than an ulp of the large one.
    const std::vector<double> values = {3.0, 3e-16, 3e-16, 3e-16};
    std::optional<ChainBatch::Run> inOrder, reversed;
    for (const bool reverse : {false, true}) {
        ChainBatch batch({10, 11, 12, 13});
        for (size_t i = 0; i < values.size(); ++i) {
            const size_t slot = reverse ? values.size() - 1 - i : i;
            std::vector<ChainBatch::Run> runs = batch.finish(slot, result(values[slot]), 0.25);
            // Only the last task to end completes the batch's single run.
            ASSERT_EQ(runs.size(), i + 1 == values.size() ? 1u : 0u) << "after slot " << slot;
            if (!runs.empty()) (reverse ? reversed : inOrder) = std::move(runs.front());
        }
    }
    for (const ChainBatch::Run *run : {&*inOrder, &*reversed}) {
        EXPECT_EQ(run->attempts, (std::vector<int64_t>{10, 11, 12, 13}));
        EXPECT_EQ(run->sum.mutations, 30u);
        EXPECT_EQ(run->sum.seedSamples, 3u);
        ASSERT_EQ(run->sum.counts.size(), 1u);
        EXPECT_EQ(run->sum.counts[0].proposed, 30u);
        EXPECT_EQ(run->sum.rays, 300u);
        EXPECT_DOUBLE_EQ(run->sum.seconds, 3.0);
        EXPECT_DOUBLE_EQ(run->loadSeconds, 1.0);
    }
    ChainImage a(makeFilmBlock(*scene)), b(makeFilmBlock(*scene));
    mergeChainResult(a, inOrder->sum, 4);
    mergeChainResult(b, reversed->sum, 4);
    EXPECT_EQ(a.tasks, 4u);
    EXPECT_TRUE(sameSplats(a.film, b.film));
    // Every value the tasks deposited, summed: the master's merge of the four tasks one by one, up to rounding.
    const ImageBlock one = merged(values);
    ASSERT_EQ(one.splatData().size(), a.film.splatData().size());
    double total = 0;
    for (size_t k = 0; k < one.splatData().size(); ++k) {
        EXPECT_NEAR(a.film.splatData()[k], one.splatData()[k], 1e-15 * std::abs(one.splatData()[k])) << k;
        total += a.film.splatData()[k];
    }
    EXPECT_GT(total, 0);
}

TEST_F(ChainBatchTest, ATaskWithoutAResultEndsTheRunBeforeIt) {
    ChainBatch batch({20, 21, 22, 23, 24});
    EXPECT_TRUE(batch.finish(1, result(2.0), 0).empty());
    EXPECT_TRUE(batch.finish(3, result(4.0), 0).empty());
    // Task 2 failed: the run of tasks 0 and 1 leaves once task 0 ends.
    EXPECT_TRUE(batch.finish(2, std::nullopt, 0).empty());
    std::vector<ChainBatch::Run> runs = batch.finish(0, result(1.0), 0);
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(runs[0].attempts, (std::vector<int64_t>{20, 21}));
    ChainImage image(makeFilmBlock(*scene));
    mergeChainResult(image, runs[0].sum, 2);
    EXPECT_TRUE(sameSplats(image.film, merged({1.0, 2.0})));
    // Tasks 3 and 4 form the last run; a task ending twice is a bug, not a result.
    runs = batch.finish(4, result(5.0), 0);
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(runs[0].attempts, (std::vector<int64_t>{23, 24}));
    EXPECT_EQ(runs[0].sum.mutations, 90u);
    EXPECT_THROW(batch.finish(4, result(5.0), 0), std::logic_error);
    // A batch whose every task failed sends nothing.
    ChainBatch failed({30, 31});
    EXPECT_TRUE(failed.finish(1, std::nullopt, 0).empty());
    EXPECT_TRUE(failed.finish(0, std::nullopt, 0).empty());
}

// A slow task may not make the results behind it pile up: once more than maxWaiting wait for it, it is set aside
// and leaves as a run of its own, and the tasks after it form a run without it.
TEST_F(ChainBatchTest, ASlowTaskIsSetAsideOnceTooManyResultsWaitForIt) {
    ChainBatch batch({40, 41, 42, 43, 44, 45}, 2);
    EXPECT_TRUE(batch.finish(1, result(2.0), 0).empty());
    EXPECT_TRUE(batch.finish(2, result(3.0), 0).empty());
    // A third result waiting for task 0: task 0 is set aside, and tasks 1-3 start the next run.
    EXPECT_TRUE(batch.finish(3, result(4.0), 0).empty());
    EXPECT_TRUE(batch.finish(5, result(6.0), 0).empty());
    std::vector<ChainBatch::Run> runs = batch.finish(4, result(5.0), 0);
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(runs[0].attempts, (std::vector<int64_t>{41, 42, 43, 44, 45}));
    EXPECT_EQ(runs[0].sum.mutations, 200u);
    ChainImage image(makeFilmBlock(*scene));
    mergeChainResult(image, runs[0].sum, 5);
    EXPECT_TRUE(sameSplats(image.film, merged({2.0, 3.0, 4.0, 5.0, 6.0})));
    // Task 0 leaves alone when it ends, once.
    runs = batch.finish(0, result(1.0), 0.5);
    ASSERT_EQ(runs.size(), 1u);
    EXPECT_EQ(runs[0].attempts, (std::vector<int64_t>{40}));
    EXPECT_EQ(runs[0].sum.mutations, 10u);
    EXPECT_DOUBLE_EQ(runs[0].loadSeconds, 0.5);
    EXPECT_THROW(batch.finish(0, result(1.0), 0), std::logic_error);

    // A task set aside that fails sends nothing; the run before it left when it was set aside.
    ChainBatch failing({50, 51, 52, 53}, 1);
    EXPECT_TRUE(failing.finish(0, result(1.0), 0).empty());
    EXPECT_TRUE(failing.finish(2, result(3.0), 0).empty());
    runs = failing.finish(3, result(4.0), 0);
    ASSERT_EQ(runs.size(), 2u);
    EXPECT_EQ(runs[0].attempts, (std::vector<int64_t>{50}));
    EXPECT_EQ(runs[1].attempts, (std::vector<int64_t>{52, 53}));
    EXPECT_TRUE(failing.finish(1, std::nullopt, 0).empty());
}

TEST_F(ChainBatchTest, OnlyTileFilmsOfOneCropWindowAdd) {
    ChainResult sum = result(1.0);
    ChainResult dense = result(2.0);
    dense.film = makeFilmBlock(*scene);
    EXPECT_THROW(addChainResult(sum, dense), std::invalid_argument);
    auto other = loadChainTestScene("cornell-box", 32);
    ChainResult larger = result(2.0);
    larger.film = makeFilmBlock(*other, BlockStorage::Tiles);
    EXPECT_THROW(addChainResult(sum, larger), std::invalid_argument);
}

}  // namespace
}  // namespace pf::test
