// The long version of test_mept_media (label "long", `make test-long`): MEPT and MEMLT with medium chains against
// BDPT and volpath at 32 x 32 with 32 independent renders each (longConvergenceSetup: 49 comparisons per case at
// 5 standard errors of a Student t with 31 degrees of freedom), on every media scene with blocks of 8, under
// budgets in samples and under `--time`. volpath is compared where it resolves the image, ring-caustic-medium's
// single scattering (test_mept_media.cpp says why not elsewhere).
#include <gtest/gtest.h>

#include "test_mept_media_common.h"

namespace pf::test {
namespace {

class LongMEPTMedia : public ::testing::TestWithParam<MediaCase> {};

TEST_P(LongMEPTMedia, Agrees) {
    const MediaCase &c = GetParam();
    expectConvergence(c.scene, "erpt", meptParams(c), mediaSetup(c, longConvergenceSetup(c.budget)), c.scene + " mept");
}

TEST_P(LongMEPTMedia, AgreesUnderTimeBudget) {
    const MediaCase &c = GetParam();
    ConvergenceSetup s = mediaSetup(c, longConvergenceSetup(c.budget));
    s.timeLimit = 4;
    expectConvergence(c.scene, "erpt", meptParams(c), s, c.scene + " mept --time 4");
}

TEST_P(LongMEPTMedia, MEMLTAgrees) {
    const MediaCase &c = GetParam();
    ConvergenceSetup s = mediaSetup(c, longConvergenceSetup(c.budget));
    s.budget = 256;
    expectConvergence(c.scene, "memlt", memltParams(s.res), s, c.scene + " memlt");
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongMEPTMedia,
                         ::testing::Values(MediaCase{"ring-caustic-medium", 3, 8, "bdpt", 16},
                                           MediaCase{"volumetric-caustic-small", 6, 8, "bdpt", 16},
                                           MediaCase{"glass-egg-largelight", 6, 8, "bdpt", 16, 8},
                                           MediaCase{"ring-caustic-medium", 2, 8, "volpath", 16}),
                         [](const auto &info) { return caseName(info.param); });

}  // namespace
}  // namespace pf::test
