// Chain tasks and the embedded Markov-chain renderer (render/chain.h, render/normalizer.h; ALGORITHMS.md
// §2.5, §9.4): a task is a pure function of its inputs (the same bits in two processes), the embedded
// renderer does not depend on the thread count, budgets split into fixed chain lengths, the merge rules
// of long chains and bursts, and the parameters of pssmlt and mmlt.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "integrators/mmlt.h"
#include "integrators/pssmlt.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "support/chain_util.h"
#include "support/process.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

constexpr uint64_t kSeed = 99;

// Task 3 of a small pssmlt or mmlt job on cornell-box, serialized: the film's splat storage, the mutation
// count and the per-type counts, byte for byte.
std::string chainTaskBytes(const std::string &type) {
    auto scene = loadChainTestScene("cornell-box", 16);
    const auto integrator = makeTestIntegrator(*scene, type, {{"luminanceSamples", "1024"}});
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*integrator);
    const Normalizer normalizer = seedChains(*scene, chains, kSeed);
    ChainTask task = chains.chainTask(*scene, normalizer, kSeed, 1, 3);
    task.mutations = 3000;
    return chainResultBytes(runChainTask(*scene, chains, kSeed, task));
}

// Run by the test below in child processes: writes the task's bytes to $PATHFARM_CHAIN_TASK_OUT.
TEST(ChainTaskChild, WriteResult) {
    const char *out = std::getenv("PATHFARM_CHAIN_TASK_OUT");
    if (!out) GTEST_SKIP() << "only run as a child of ChainTask.SameBitsInTwoProcesses";
    std::ofstream(out, std::ios::binary) << chainTaskBytes(std::getenv("PATHFARM_CHAIN_TASK_TYPE"));
}

// §2.5, §9.4: a task rerun in another process (a retried farm task) returns the same bits.
TEST(ChainTask, SameBitsInTwoProcesses) {
    const std::string dir = tempDir("chain-task-processes"), self = selfPath();
    ASSERT_FALSE(self.empty());
    for (const std::string type : {"pssmlt", "mmlt"}) {
        std::vector<std::string> results;
        for (int k = 0; k < 2; ++k) {
            const std::string out = dir + "/" + type + std::to_string(k) + ".bin";
            const ProcessResult p = runCommand("PATHFARM_CHAIN_TASK_OUT=" + out + " PATHFARM_CHAIN_TASK_TYPE=" + type +
                                               " " + self + " --gtest_filter=ChainTaskChild.WriteResult");
            ASSERT_EQ(p.exitCode, 0) << p.output;
            results.push_back(readFile(out));
        }
        ASSERT_GT(results[0].size(), 16u * 16u * 3u * sizeof(double)) << type;
        EXPECT_TRUE(results[0] == results[1]) << type << ": two processes disagree";
        EXPECT_TRUE(results[0] == chainTaskBytes(type)) << type << ": this process disagrees";
    }
}

// The embedded renderer merges chains in task order: one thread or two give the same bits; and a
// different seed gives a different image.
TEST(ChainTask, EmbeddedRenderIsIndependentOfThreads) {
    auto scene = loadChainTestScene("cornell-box", 16);
    for (const std::string type : {"pssmlt", "mmlt"}) {
        const auto integrator =
            makeTestIntegrator(*scene, type, {{"luminanceSamples", "1024"}, {"directSamples", "2"}});
        std::vector<Bitmap> images;
        for (int threads : {1, 2, 2}) {
            RenderOptions opt;
            opt.spp = 200;  // 51,200 mutations: four chains
            opt.seed = threads == 2 && images.size() == 2 ? kSeed + 1 : kSeed;
            opt.threads = threads;
            RenderStats stats;
            images.push_back(integrator->render(*scene, opt, stats));
            EXPECT_EQ(stats.samples, 200u * 256u);
            EXPECT_EQ(stats.samplesPerPixel, 200);
        }
        EXPECT_TRUE(images[0].rgb == images[1].rgb) << type;
        EXPECT_FALSE(images[0].rgb == images[2].rgb) << type;
    }
}

// --spp is mutations per pixel, split into chains of fixed lengths that differ by at most one; under
// --time every chain has the fixed length.
TEST(ChainTask, BudgetSplitsIntoFixedChains) {
    auto scene = loadChainTestScene("cornell-box", 16);
    const auto integrator = makeTestIntegrator(*scene, "pssmlt", {{"luminanceSamples", "1024"}});
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*integrator);
    std::vector<SeedingResult> seeds;
    for (const SeedingTask &t : seedingTasks(*scene))
        seeds.push_back(runSeedingTask(*scene, chains.seeding(*scene), kSeed, t));
    const Normalizer normalizer(std::move(seeds));
    for (int64_t spp : {1, 255, 256, 257, 1000}) {
        const uint64_t count = chains.chainTaskCount(*scene, spp);
        uint64_t total = 0, lo = UINT64_MAX, hi = 0;
        for (uint64_t i = 0; i < count; ++i) {
            const ChainTask t = chains.chainTask(*scene, normalizer, kSeed, spp, i);
            EXPECT_EQ(t.index, i);
            ASSERT_EQ(t.seeds.size(), 1u);
            total += t.mutations;
            lo = std::min(lo, t.mutations);
            hi = std::max(hi, t.mutations);
        }
        EXPECT_EQ(total, static_cast<uint64_t>(spp) * 256u) << spp;
        EXPECT_LE(hi - lo, 1u) << spp;
        EXPECT_LE(hi, 1u << 14) << spp;
    }
    EXPECT_EQ(chains.chainTask(*scene, normalizer, kSeed, 0, 12345).mutations, 1u << 14);
    // The starts depend on the chain index only, not on the budget.
    EXPECT_EQ(chains.chainTask(*scene, normalizer, kSeed, 0, 7).seeds[0].record.sampleIndex,
              chains.chainTask(*scene, normalizer, kSeed, 1000, 7).seeds[0].record.sampleIndex);

    RenderOptions opt;
    opt.timeLimit = 0.5;
    opt.seed = kSeed;
    opt.threads = 2;
    RenderStats stats;
    integrator->render(*scene, opt, stats);
    EXPECT_GT(stats.samples, 0u);
    EXPECT_EQ(stats.samples % (1u << 14), 0u) << "a chain was cut by the clock";
}

// §2.5: long chains are normalized by b̂ / (total mutations) after summing; bursts are summed and divided by
// the passes merged (integrators/erpt.h).
TEST(ChainTask, MergeRules) {
    auto scene = loadChainTestScene("cornell-box", 4);
    const Film &film = scene->sensor().film();
    const auto result = [&](double value, uint64_t mutations) {
        ChainResult r{makeFilmBlock(*scene), mutations, 0, {{"a", mutations, mutations / 2}}, {}, 0, 1.0};
        r.film.splat(Vec2(1.5, 2.5), Spectrum(value));
        return r;
    };
    ChainImage image(makeFilmBlock(*scene));
    mergeChainResult(image, result(3.0, 100));
    mergeChainResult(image, result(5.0, 300));
    EXPECT_EQ(image.mutations, 400u);
    ASSERT_EQ(image.counts.size(), 1u);
    EXPECT_EQ(image.counts[0].proposed, 400u);
    EXPECT_EQ(image.counts[0].accepted, 200u);
    EXPECT_DOUBLE_EQ(image.seconds, 2.0);
    EXPECT_EQ(image.tasks, 2u);
    const auto longChains = makeTestIntegrator(*scene, "pssmlt", {});
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*longChains);
    const Bitmap developed = developChains(film, image, chains.chainImageScale(*scene, 0, image, 2.0));
    EXPECT_FLOAT_EQ(developed.get(1, 2).r, static_cast<float>(2.0 * 8.0 / 400.0));
    EXPECT_EQ(developed.get(2, 1).r, 0.0f);
    // A 4x4 erpt render's pass is one task: two tasks are two passes, and the image is their mean.
    const auto erpt = makeTestIntegrator(*scene, "erpt", {});
    const auto &bursts = dynamic_cast<const ChainIntegrator &>(*erpt);
    ASSERT_EQ(bursts.tasksPerPass(*scene, 0), 1u);
    EXPECT_FLOAT_EQ(developChains(film, image, bursts.chainImageScale(*scene, 0, image, 2.0)).get(1, 2).g, 4.0f);
    ChainImage empty(makeFilmBlock(*scene));
    EXPECT_EQ(chains.chainImageScale(*scene, 0, empty, 2.0), 0.0);
    EXPECT_EQ(bursts.chainImageScale(*scene, 0, empty, 2.0), 0.0);

    const ChainSeed burst{{}, 0.5};
    EXPECT_EQ(chainDepositScale(ChainKind::Long, burst, 100), 1.0);
    EXPECT_DOUBLE_EQ(chainDepositScale(ChainKind::Burst, burst, 100), 0.005);
}

// Mitsuba's directSamples: 0 hides the paths of at most two edges, -1 leaves them to the chains, and a
// positive count renders them with volpath beside the chains.
TEST(ChainTask, DirectSamplesSplitsTheImage) {
    auto scene = loadChainTestScene("cornell-box", 8);
    const auto total = [&](const std::string &directSamples) {
        RenderOptions opt;
        opt.spp = 16;
        opt.seed = kSeed;
        opt.threads = 2;
        RenderStats stats;
        const Bitmap img = makeTestIntegrator(*scene, "pssmlt", {{"maxDepth", "2"}, {"directSamples", directSamples}})
                               ->render(*scene, opt, stats);
        double sum = 0;
        for (float v : img.rgb) sum += v;
        return sum;
    };
    EXPECT_EQ(total("0"), 0.0);
    EXPECT_GT(total("-1"), 0.0);
    EXPECT_GT(total("4"), 0.0);
    const auto pss = makeTestIntegrator(*scene, "pssmlt", {});
    const auto &p = dynamic_cast<const PrimarySampleIntegrator &>(*pss);
    EXPECT_EQ(p.directSamples(), 16);
    EXPECT_NE(p.directIntegrator(), nullptr);
    EXPECT_EQ(p.minDepth(), 3);
}

TEST(ChainTask, Parameters) {
    auto scene = loadChainTestScene("cornell-box", 4);
    EXPECT_NE(integratorNames().find("pssmlt"), std::string::npos);
    EXPECT_NE(integratorNames().find("mmlt"), std::string::npos);
    const auto fails = [&](const std::string &type, const std::string &name, const std::string &value,
                           const std::string &message) {
        try {
            makeTestIntegrator(*scene, type, {{name, value}});
            ADD_FAILURE() << type << " accepted " << name << "=" << value;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    };
    for (const std::string type : {"pssmlt", "mmlt"}) {
        EXPECT_NO_THROW(makeTestIntegrator(*scene, type,
                                           {{"maxDepth", "5"},
                                            {"rrDepth", "3"},
                                            {"directSamples", "-1"},
                                            {"luminanceSamples", "5000"},
                                            {"pLarge", "0.5"},
                                            {"kelemenStyleWeights", "false"},
                                            {"directSampling", "false"},
                                            {"mutationSizeLow", "0.001"},
                                            {"mutationSizeHigh", "0.02"},
                                            {"twoStage", "true"},
                                            {"firstStageSizeReduction", "8"}}));
        fails(type, "firstStageSizeReduction", "0", "firstStageSizeReduction");
        fails(type, "noSuchParameter", "1", "noSuchParameter");
        fails(type, "pLarge", "1.5", "pLarge");
        fails(type, "mutationSizeLow", "0.5", "mutationSizeLow");
        fails(type, "maxDepth", "0", "maxDepth");
        fails(type, "directSamples", "-2", "directSamples");
        fails(type, "luminanceSamples", "0", "luminanceSamples");
    }
    EXPECT_NO_THROW(makeTestIntegrator(*scene, "pssmlt", {{"bidirectional", "true"}}));
    fails("pssmlt", "bidirectional", "false", "unidirectional");
    fails("mmlt", "bidirectional", "true", "bidirectional");
    EXPECT_EQ(makeTestIntegrator(*scene, "pssmlt", {})->name(), "pssmlt");
    EXPECT_EQ(makeTestIntegrator(*scene, "mmlt", {})->name(), "mmlt");
}

}  // namespace
}  // namespace pf::test
