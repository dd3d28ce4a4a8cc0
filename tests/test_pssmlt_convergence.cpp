// Convergence of PSSMLT and MMLT (ALGORITHMS.md §9.1.1): both agree with a BDPT reference on cornell-box,
// veach-mis and veach-bidir, every path left to the chains (directSamples = -1). Block means of images
// rendered with independent seeds: each render (seeding, b̂ and chains) is an independent estimate, so the
// seed-to-seed spread of a block mean is its standard error whatever the correlation along the chains.
// This is the short version of test_long_pssmlt (larger images, more runs, Mitsuba's default direct
// component as well), sized for the default suite.
#include <gtest/gtest.h>

#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int referenceSpp, mutationsPerPixel;
};

class ShortConvergence : public ::testing::TestWithParam<Case> {};

TEST_P(ShortConvergence, AgreesWithBDPT) {
    const Case &c = GetParam();
    constexpr int kRes = 24, kBlock = 8, kSeeds = 16;
    auto scene = loadChainTestScene(c.scene, kRes);
    const BlockStats reference =
        blockStats(*scene, *makeTestIntegrator(*scene, "bdpt", {}), kBlock, kSeeds, c.referenceSpp, 1);
    for (const std::string type : {"pssmlt", "mmlt"}) {
        const auto integrator = makeTestIntegrator(
            *scene, type, {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(kRes * kRes * 8)}});
        const BlockStats chains = blockStats(*scene, *integrator, kBlock, kSeeds, c.mutationsPerPixel, 2);
        // 36 comparisons per case at 4.5 standard errors of a Student t with 15 degrees of freedom.
        expectBlocksAgree(reference, chains, 4.5, 0.04, 0.02, c.scene + " " + type);
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ShortConvergence,
                         ::testing::Values(Case{"cornell-box", 32, 64}, Case{"veach-mis", 32, 64},
                                           Case{"veach-bidir", 32, 64}),
                         [](const auto &info) {
                             std::string n = info.param.scene;
                             std::replace(n.begin(), n.end(), '-', '_');
                             return n;
                         });

}  // namespace
}  // namespace pf::test
