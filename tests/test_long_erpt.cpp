// The long version of test_erpt (label "long", `make test-long`): `erpt` against a BDPT reference at
// 32 x 32 with 32 independent renders each, with Mitsuba's split (a separate direct component, of 64 samples
// per pixel here) and with every path left to the chains, and each of Veach's mutations alone on every scene
// where it applies (ALGORITHMS.md §5.2: bursts stay unbiased with any transition rule that keeps the target, so
// each one is tested by itself).
#include <gtest/gtest.h>

#include "test_mlt_common.h"

namespace pf::test {
namespace {

struct DefaultsCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const DefaultsCase &c, std::ostream *os) {
        *os << c.scene << (c.separateDirect ? " separateDirect" : "");
    }
    std::string scene;
    bool separateDirect;
};

class LongERPTConvergence : public ::testing::TestWithParam<DefaultsCase> {};

// 49 comparisons per case at 5 standard errors of a Student t with 31 degrees of freedom. The direct component
// takes 64 samples per pixel rather than Mitsuba's 16: at 16, one sample that hits veach-mis's smallest lamp
// (radiance 3039.64) adds 190 to its pixel, 0.19 to the image's mean of 0.375, which 32 renders cannot average
// (their means fell in two groups, 24 near 0.30 and 8 near 0.49), and the comparison is of the chains.
TEST_P(LongERPTConvergence, AgreesWithBDPT) {
    const DefaultsCase &c = GetParam();
    const std::vector<std::pair<std::string, std::string>> params = {{"directSamples", c.separateDirect ? "64" : "-1"},
                                                                     {"chainLength", "200"}};
    expectConvergence(c.scene, "erpt", params, longConvergenceSetup(16), c.scene + " erpt");
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongERPTConvergence,
                         ::testing::Values(DefaultsCase{"cornell-box", false}, DefaultsCase{"cornell-box", true},
                                           DefaultsCase{"veach-mis", false}, DefaultsCase{"veach-mis", true},
                                           DefaultsCase{"veach-bidir", false}, DefaultsCase{"veach-bidir", true}),
                         [](const auto &info) {
                             return gtestName(info.param.scene + (info.param.separateDirect ? "_direct" : "_chains"));
                         });

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene << " " << mutationName(c.type); }
    std::string scene;
    MutationType type;
};

class LongSingleMutationBursts : public ::testing::TestWithParam<Case> {};

TEST_P(LongSingleMutationBursts, AgreeWithBDPT) {
    expectSingleMutationConvergence(GetParam().scene, GetParam().type, longConvergenceSetup(16));
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, LongSingleMutationBursts,
    ::testing::Values(Case{"cornell-box", MutationType::Bidirectional}, Case{"cornell-box", MutationType::LensSubpath},
                      Case{"cornell-box", MutationType::Lens}, Case{"cornell-box", MutationType::Caustic},
                      Case{"veach-mis", MutationType::Bidirectional}, Case{"veach-mis", MutationType::LensSubpath},
                      Case{"veach-mis", MutationType::Lens}, Case{"veach-mis", MutationType::Caustic},
                      Case{"veach-bidir", MutationType::Bidirectional}, Case{"veach-bidir", MutationType::LensSubpath},
                      Case{"veach-bidir", MutationType::Lens}, Case{"veach-bidir", MutationType::Caustic},
                      Case{"pool", MutationType::Lens}, Case{"pool", MutationType::MultiChain},
                      Case{"pool-underwater", MutationType::Caustic}),
    [](const auto &info) { return gtestName(info.param.scene + "_" + mutationName(info.param.type)); });

}  // namespace
}  // namespace pf::test
