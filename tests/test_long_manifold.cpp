// The long version of test_mept (label "long", `make test-long`): `mept` and `memlt` against a BDPT reference
// at 32 x 32 with 32 independent renders each, on scenes without specular chains (cornell-box), with light
// through glass (veach-bidir), two refraction chains (the pool) and a caustic off a smooth gold ring seen
// directly and in the ring (ring-caustic, up to 3 edges: test_mept says why; ALGORITHMS.md §5.4, §9.1).
// TORUS is left out: its light reaches the torus only through glass, which is what BDPT (the reference)
// samples worst, and with 64 seeds per pixel and a 128 spp reference the comparison was too noisy to mean
// anything.
#include <gtest/gtest.h>

#include "test_mlt_common.h"

namespace pf::test {
namespace {

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int budget;
    int maxDepth = 0;  // longest paths (0: the scene's)
};

class LongMEPTConvergence : public ::testing::TestWithParam<Case> {};

// 49 comparisons per case at 5 standard errors of a Student t with 31 degrees of freedom.
TEST_P(LongMEPTConvergence, AgreesWithBDPT) {
    expectSingleMutationConvergence(GetParam().scene, MutationType::Manifold,
                                    longConvergenceSetup(GetParam().budget, GetParam().maxDepth));
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongMEPTConvergence,
                         ::testing::Values(Case{"cornell-box", 16}, Case{"veach-bidir", 16}, Case{"pool", 16},
                                           Case{"pool-underwater", 16}, Case{"ring-caustic", 16, 3}),
                         [](const auto &info) { return gtestName(info.param.scene); });

class LongMEMLTConvergence : public ::testing::TestWithParam<Case> {};

// 49 comparisons per case as above, from a seeding pool of 16 samples per pixel. Chains are 2^14 mutations
// long, so 256 mutations per pixel make 16 chains per render; ring-caustic, whose regions mix slowly under
// the bidirectional mutation (test_mept), gets 64.
TEST_P(LongMEMLTConvergence, AgreesWithBDPT) {
    expectConvergence(GetParam().scene, "memlt",
                      {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(32 * 32 * 16)}},
                      longConvergenceSetup(GetParam().budget, GetParam().maxDepth), GetParam().scene + " memlt");
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongMEMLTConvergence,
                         ::testing::Values(Case{"cornell-box", 256}, Case{"veach-bidir", 512},
                                           Case{"ring-caustic", 1024, 3}),
                         [](const auto &info) { return gtestName(info.param.scene); });

}  // namespace
}  // namespace pf::test

// The glossy extension of the manifold perturbation (offset manifolds, ALGORITHMS.md §6.6): the long version of
// test_glossy_manifold's MEPT case on GLOSSY SPHERES, with the other cases' long set-up (longConvergenceSetup).
namespace pf::test {
namespace {

TEST(LongGlossyManifold, MEPTAgreesWithBDPT) {
    expectSingleMutationConvergence("glossy-spheres", MutationType::Manifold, longConvergenceSetup(16));
}

}  // namespace
}  // namespace pf::test
