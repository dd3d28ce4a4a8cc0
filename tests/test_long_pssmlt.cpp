// The long version of test_pssmlt_convergence (CTest label "long", `make test-long`): PSSMLT and MMLT
// agree with a BDPT reference on cornell-box, veach-mis and veach-bidir at 32x32 with 16 blocks, with
// every path left to the chains and with Mitsuba's default separate direct component, and PSSMLT with
// Veach's expected values instead of Kelemen's weights. Independent repeated runs give the standard
// errors (ALGORITHMS.md §9.1), tighter than the short version's.
#include <gtest/gtest.h>

#include <thread>

#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

struct Config {
    std::string type;
    std::vector<std::pair<std::string, std::string>> params;
};

class LongConvergence : public ::testing::TestWithParam<std::string> {};

TEST_P(LongConvergence, AgreesWithBDPT) {
    constexpr int kRes = 32, kBlock = 8, kSeeds = 24, kMutationsPerPixel = 128;
    // Renders are the same bits on any number of threads, so this uses them all.
    const int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    auto scene = loadChainTestScene(GetParam(), kRes);
    const BlockStats reference =
        blockStats(*scene, *makeTestIntegrator(*scene, "bdpt", {}), kBlock, kSeeds, 256, 1, threads);
    const std::string luminanceSamples = std::to_string(kRes * kRes * 16);
    const std::vector<Config> configs = {
        {"pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", luminanceSamples}}},
        {"pssmlt", {{"luminanceSamples", luminanceSamples}}},
        {"pssmlt", {{"directSamples", "-1"}, {"luminanceSamples", luminanceSamples}, {"kelemenStyleWeights", "false"}}},
        {"mmlt", {{"directSamples", "-1"}, {"luminanceSamples", luminanceSamples}}},
        {"mmlt", {{"luminanceSamples", luminanceSamples}}},
    };
    for (size_t i = 0; i < configs.size(); ++i) {
        const Config &c = configs[i];
        const BlockStats chains = blockStats(*scene, *makeTestIntegrator(*scene, c.type, c.params), kBlock, kSeeds,
                                             kMutationsPerPixel, 100 * (i + 1), threads);
        std::string what = GetParam() + " " + c.type;
        for (const auto &[name, value] : c.params) what += " " + name + "=" + value;
        // 49 comparisons per configuration at 5 standard errors of a Student t with 23 degrees of freedom.
        expectBlocksAgree(reference, chains, 5.0, 0.03, 0.015, what);
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongConvergence, ::testing::Values("cornell-box", "veach-mis", "veach-bidir"),
                         [](const auto &info) {
                             std::string n = info.param;
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

}  // namespace
}  // namespace pf::test
