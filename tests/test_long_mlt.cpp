// The long version of test_mlt's convergence (label "long", `make test-long`): `mlt` against a BDPT
// reference on cornell-box, veach-mis and veach-bidir at 32 x 32 with 32 independent renders each, with
// Mitsuba's defaults (the direct component rendered by volpath, chains for paths of three edges or more) and
// with every path left to the chains, and Veach's bidirectional mutation alone (the only ergodic one).
#include <gtest/gtest.h>

#include "test_mlt_common.h"

namespace pf::test {
namespace {

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene << " " << c.label; }
    std::string scene, label;
    std::vector<std::pair<std::string, std::string>> params;
    int mutationsPerPixel;
};

class LongMLTConvergence : public ::testing::TestWithParam<Case> {};

// 49 comparisons per case at 5 standard errors of a Student t with 31 degrees of freedom.
TEST_P(LongMLTConvergence, AgreesWithBDPT) {
    const Case &c = GetParam();
    ConvergenceSetup s = longConvergenceSetup(c.mutationsPerPixel);
    s.maxMedianError = 0.03;
    s.maxImageError = 0.015;
    expectConvergence(c.scene, "mlt", c.params, s, c.scene + " mlt " + c.label);
}

const std::vector<std::pair<std::string, std::string>> kChainsOnly = {{"directSamples", "-1"}}, kDefaults = {},
                                                       kBidirectionalOnly = {{"directSamples", "-1"},
                                                                             {"lensSubpathMutation", "false"},
                                                                             {"lensPerturbation", "false"},
                                                                             {"causticPerturbation", "false"},
                                                                             {"multiChainPerturbation", "false"}};

INSTANTIATE_TEST_SUITE_P(Scenes, LongMLTConvergence,
                         ::testing::Values(Case{"cornell-box", "chains", kChainsOnly, 256},
                                           Case{"cornell-box", "defaults", kDefaults, 256},
                                           Case{"cornell-box", "bidirectional", kBidirectionalOnly, 256},
                                           Case{"veach-mis", "chains", kChainsOnly, 2048},
                                           Case{"veach-mis", "defaults", kDefaults, 2048},
                                           Case{"veach-bidir", "chains", kChainsOnly, 1024},
                                           Case{"veach-bidir", "defaults", kDefaults, 1024},
                                           Case{"veach-bidir", "bidirectional", kBidirectionalOnly, 1024}),
                         [](const auto &info) { return gtestName(info.param.scene + "_" + info.param.label); });

}  // namespace
}  // namespace pf::test
