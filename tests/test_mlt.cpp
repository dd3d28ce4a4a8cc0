// Veach's path-space MLT (`mlt`): convergence to a BDPT reference on cornell-box, veach-mis and veach-bidir
// (ALGORITHMS.md §9.1.1), the reproducibility of its chain tasks and of ERPT's (§2.5, §9.4), and its
// parameters. Convergence compares block means of images rendered with independent seeds: each render
// (seeding, b̂ and chains) is an independent estimate, so the seed-to-seed spread of a block mean is its
// standard error whatever the correlation along the chains. Short version; test_long_mlt.cpp has larger
// images, more runs and Mitsuba's separate direct component.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "integrators/mlt.h"
#include "render/normalizer.h"
#include "support/chain_util.h"
#include "support/process.h"
#include "test_mlt_common.h"

namespace pf::test {
namespace {

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int mutationsPerPixel;
};

class MLTConvergence : public ::testing::TestWithParam<Case> {};

// Every path left to the chains; 37 comparisons per case at 4.5 standard errors of a Student t with 15
// degrees of freedom.
TEST_P(MLTConvergence, AgreesWithBDPT) {
    const Case &c = GetParam();
    ConvergenceSetup s;
    s.res = 24;
    s.budget = c.mutationsPerPixel;
    s.referenceSpp = 32;
    s.maxMedianError = 0.045;
    s.maxImageError = 0.02;
    expectConvergence(c.scene, "mlt", {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(24 * 24 * 8)}}, s,
                      c.scene + " mlt");
}

// Mutations per pixel such that the chains' errors are about those of the 32 spp reference: long chains
// need many more steps on veach-mis, whose small bright lights are reached by few of them.
INSTANTIATE_TEST_SUITE_P(Scenes, MLTConvergence,
                         ::testing::Values(Case{"cornell-box", 64}, Case{"veach-mis", 512}, Case{"veach-bidir", 256}),
                         [](const auto &info) { return gtestName(info.param.scene); });

constexpr uint64_t kSeed = 1234;

// Task 1 of a small job of `type` (mlt or erpt) on veach-bidir, serialized: the film's splats, the
// mutation count and the per-type counts, byte for byte.
std::string chainTaskBytes(const std::string &type) {
    auto scene = loadMLTTestScene("veach-bidir", 16, 4);
    const auto integrator = makeTestIntegrator(*scene, type, {{"luminanceSamples", "1024"}, {"directSamples", "-1"}});
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*integrator);
    const Normalizer normalizer = seedChains(*scene, chains, kSeed);
    ChainTask task = chains.chainTask(*scene, normalizer, kSeed, 4, 1);
    if (type == "mlt") task.mutations = 5000;
    return chainResultBytes(runChainTask(*scene, chains, kSeed, task));
}

// Run by the test below in child processes: writes the task's bytes to $PATHFARM_MLT_TASK_OUT.
TEST(MLTChainTaskChild, WriteResult) {
    const char *out = std::getenv("PATHFARM_MLT_TASK_OUT");
    if (!out) GTEST_SKIP() << "only run as a child of MLTChainTask.SameBitsInTwoProcesses";
    std::ofstream(out, std::ios::binary) << chainTaskBytes(std::getenv("PATHFARM_MLT_TASK_TYPE"));
}

// A retried farm task returns the same bits, in this process and in two others.
TEST(MLTChainTask, SameBitsInTwoProcesses) {
    const std::string dir = tempDir("mlt-chain-task-processes");
    const std::string self = selfPath();
    ASSERT_FALSE(self.empty());
    for (const std::string type : {"mlt", "erpt"}) {
        std::vector<std::string> results;
        for (int k = 0; k < 2; ++k) {
            const std::string out = dir + "/" + type + std::to_string(k) + ".bin";
            const ProcessResult p = runCommand("PATHFARM_MLT_TASK_OUT=" + out + " PATHFARM_MLT_TASK_TYPE=" + type +
                                               " " + self + " --gtest_filter=MLTChainTaskChild.WriteResult");
            ASSERT_EQ(p.exitCode, 0) << p.output;
            results.push_back(readFile(out));
        }
        ASSERT_GT(results[0].size(), 16u * 16u * 3u * sizeof(double)) << type;
        EXPECT_TRUE(results[0] == results[1]) << type << ": two processes disagree";
        EXPECT_TRUE(results[0] == chainTaskBytes(type)) << type << ": this process disagrees";
    }
}

TEST(MLTParameters, MitsubaNamesAndChecks) {
    auto scene = loadMLTTestScene("cornell-box", 8, 4);
    // Mitsuba 0.6's mlt parameters are understood.
    EXPECT_NO_THROW(makeTestIntegrator(*scene, "mlt",
                                       {{"maxDepth", "5"},
                                        {"rrDepth", "7"},
                                        {"directSamples", "-1"},
                                        {"luminanceSamples", "5000"},
                                        {"twoStage", "true"},
                                        {"firstStageSizeReduction", "8"},
                                        {"bidirectionalMutation", "true"},
                                        {"lensPerturbation", "false"},
                                        {"causticPerturbation", "true"},
                                        {"multiChainPerturbation", "false"},
                                        {"lensSubpathMutation", "false"},
                                        {"manifoldPerturbation", "false"},
                                        {"lambda", "60.0"},
                                        {"probFactor", "60.0"}}));
    // The defaults: Veach's full set of mutations.
    const auto defaults = makeTestIntegrator(*scene, "mlt", {});
    const auto &mlt = dynamic_cast<const MLT &>(*defaults);
    std::vector<std::string> names;
    for (const MutationCount &c : mlt.mutationTypes()) names.push_back(c.name);
    EXPECT_EQ(names,
              (std::vector<std::string>{"bidirectional", "lensSubpath", "lens", "caustic", "multiChain", "none"}));
    EXPECT_EQ(mlt.directSamples(), 16);
    EXPECT_EQ(mlt.minVertices(), 4) << "the direct component is rendered apart by default";
    EXPECT_EQ(mlt.seeding(*scene).samplesPerPixel, (100000 + 63) / 64) << "luminanceSamples defaults to 100000";
    const auto fails = [&](const std::vector<std::pair<std::string, std::string>> &params, const std::string &what) {
        try {
            makeTestIntegrator(*scene, "mlt", params);
            ADD_FAILURE() << "accepted " << params.front().first;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    fails({{"probFactor", "0.0"}}, "lambda");
    fails({{"firstStageSizeReduction", "0"}}, "firstStageSizeReduction");
    fails({{"maxDepth", "0"}}, "maxDepth");
    fails({{"rrDepth", "0"}}, "rrDepth");
    fails({{"directSamples", "-2"}}, "directSamples");
    fails({{"luminanceSamples", "0"}}, "luminanceSamples");
    fails({{"bidirectionalMutation", "false"},
           {"lensSubpathMutation", "false"},
           {"lensPerturbation", "false"},
           {"causticPerturbation", "false"},
           {"multiChainPerturbation", "false"}},
          "at least one mutation");
    fails({{"pLarge", "0.3"}}, "pLarge");
}

}  // namespace
}  // namespace pf::test
