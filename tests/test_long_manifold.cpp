// The long version of test_mept (label "long", `make test-long`): `mept` and `memlt` against a BDPT reference
// at 32 x 32 with 32 independent renders each, on scenes without specular chains (cornell-box), with light
// through glass (veach-bidir) and two refraction chains (the pool; ALGORITHMS.md §5.4, §9.1). ring-caustic and
// TORUS are left out: with 64 seeds per pixel and a 128 spp BDPT reference both are still too noisy for the
// comparison to mean anything (median block errors 6% and 9%, image errors 2x and 1.3x the bound); TORUS's
// light reaches the torus only through glass, which is what BDPT (the reference) samples worst.
#include <gtest/gtest.h>

#include "test_mlt_common.h"

namespace pf::test {
namespace {

ConvergenceSetup longSetup(int budget) {
    ConvergenceSetup s;
    s.res = 32;
    s.seeds = 32;
    s.referenceSpp = 128;
    s.budget = budget;
    s.sigmas = 5;
    s.maxMedianError = 0.04;
    s.maxImageError = 0.02;
    return s;
}

struct Case {
    std::string scene;
    int budget;
};

std::string testName(std::string n) {
    std::replace(n.begin(), n.end(), '-', '_');
    return n;
}

class LongMEPTConvergence : public ::testing::TestWithParam<Case> {};

// 49 comparisons per case at 5 standard errors of a Student t with 31 degrees of freedom.
TEST_P(LongMEPTConvergence, AgreesWithBDPT) {
    expectSingleMutationConvergence(GetParam().scene, MutationType::Manifold, longSetup(GetParam().budget));
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongMEPTConvergence,
                         ::testing::Values(Case{"cornell-box", 16}, Case{"veach-bidir", 16}, Case{"pool", 16},
                                           Case{"pool-underwater", 16}),
                         [](const auto &info) { return testName(info.param.scene); });

class LongMEMLTConvergence : public ::testing::TestWithParam<Case> {};

TEST_P(LongMEMLTConvergence, AgreesWithBDPT) {
    expectConvergence(GetParam().scene, "memlt",
                      {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(32 * 32 * 16)}},
                      longSetup(GetParam().budget), GetParam().scene + " memlt");
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongMEMLTConvergence,
                         ::testing::Values(Case{"cornell-box", 256}, Case{"veach-bidir", 512}),
                         [](const auto &info) { return testName(info.param.scene); });

}  // namespace
}  // namespace pf::test
