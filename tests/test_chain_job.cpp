// The task list of a Markov-chain job (render/chain_job.h): on large films the direct component's tasks grow
// from one sample per pixel to chunks (one sample per kDirectChunkPixels pixels), each comes before the first pass
// whose share of the budget owes one of its samples, and together they hold exactly the direct samples, each once.
#include <gtest/gtest.h>

#include <algorithm>

#include "render/chain.h"
#include "render/chain_job.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

// A seeded erpt job of cornell-box at res² with `directSamples`, `spp` rounds (0: a time budget).
struct SeededJob {
    SeededJob(int res, int directSamples, int64_t spp)
        : scene(loadChainTestScene("cornell-box", res)),
          integrator(makeTestIntegrator(
              *scene, "erpt", {{"directSamples", std::to_string(directSamples)}, {"luminanceSamples", "500"}})),
          chains(dynamic_cast<const ChainIntegrator &>(*integrator)),
          job(*scene, chains, 3, spp) {
        for (uint64_t i = 0; i < job.seedingTaskCount(); ++i)
            job.mergeSeeding(chains.runSeeding(*scene, spp, 3, job.seedingTask(i)));
    }
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Integrator> integrator;
    const ChainIntegrator &chains;
    ChainJob job;
};

TEST(ChainJobDirectTasks, LargeFilmsTakeSeveralSamplesPerTaskEachSampleOnce) {
    // 640² = 409600 pixels: chunks of 3 samples; 7 samples make tasks of 1, 1, 2 and 3.
    SeededJob s(640, 7, 1);
    const ChainJob &job = s.job;
    ASSERT_EQ(job.directChunk(), 3);
    ASSERT_EQ(job.directTaskCount(), 4u);
    const int64_t sizes[] = {1, 1, 2, 3};
    const auto tasksFor = [](uint64_t owed) -> uint64_t { return owed <= 2 ? owed : owed <= 4 ? 3 : 4; };
    const uint64_t perPass = job.tasksPerPass(), P = s.chains.chainTaskCount(*s.scene, 1) / perPass;
    EXPECT_EQ(job.taskCount(), job.firstChainTask() + P * perPass + 4);
    int64_t samples = 0;
    uint64_t chainTasks = 0, passes = 0, directSeen = 0;
    for (uint64_t t = job.firstChainTask(); t < job.taskCount(); ++t) {
        if (job.phaseOf(t) == ChainJob::Phase::Direct) {
            const ImageTask d = job.directTask(t);
            EXPECT_EQ(d.firstSample, samples) << "task " << t;
            EXPECT_EQ(d.sampleCount, sizes[std::min<uint64_t>(directSeen, 3)]) << "task " << t;
            samples += d.sampleCount;
            ++directSeen;
            continue;
        }
        if (chainTasks % perPass == 0) {
            // Before pass k the pace owes ceil((k + 1) D / P) samples: each task comes as soon as one of its
            // samples is owed, so the samples issued are at least those owed and at most twice as many.
            const uint64_t owed = std::min<uint64_t>(7, ((passes + 1) * 7 + P - 1) / P);
            EXPECT_EQ(directSeen, tasksFor(owed)) << "before pass " << passes;
            EXPECT_GE(samples, static_cast<int64_t>(owed)) << "before pass " << passes;
            EXPECT_LE(samples, 2 * static_cast<int64_t>(owed)) << "before pass " << passes;
            ++passes;
        }
        ++chainTasks;
    }
    EXPECT_EQ(samples, 7);
    EXPECT_EQ(directSeen, 4u);
    EXPECT_GT(passes, 3u);
    EXPECT_EQ(passes, P);
    EXPECT_EQ(chainTasks, passes * perPass);
}

TEST(ChainJobDirectTasks, ATimeBudgetGrowsToWholeChunks) {
    SeededJob s(640, 7, 0);
    const ChainJob &job = s.job;
    int64_t next = 0;
    for (uint64_t t = job.firstChainTask(), direct = 0; direct < 6; ++t) {
        if (job.phaseOf(t) != ChainJob::Phase::Direct) continue;
        const ImageTask d = job.directTask(t);
        EXPECT_EQ(d.firstSample, next);
        EXPECT_EQ(d.sampleCount, direct < 2 ? 1 : direct == 2 ? 2 : 3);
        next += d.sampleCount;
        ++direct;
    }
}

TEST(ChainJobDirectTasks, SmallFilmsKeepOneSamplePerTask) {
    // Up to kDirectChunkPixels pixels (362²) a direct task holds one sample, as before; and never more samples
    // than the direct component has.
    EXPECT_EQ(SeededJob(256, 5, 1).job.directChunk(), 1);
    EXPECT_EQ(SeededJob(256, 5, 1).job.directTaskCount(), 5u);
    EXPECT_EQ(SeededJob(1024, 2, 1).job.directChunk(), 2);
    EXPECT_EQ(SeededJob(1024, 2, 1).job.directTaskCount(), 2u);
}

}  // namespace
}  // namespace pf::test
