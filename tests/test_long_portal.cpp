// The long version of test_portal's comparison (CTest label "long"): mlt with the portal perturbation against
// BDPT and against mlt without it on the three portal scenes at 32 x 32, paths of up to 5 edges (3 in the box),
// 32 renders.
#include <gtest/gtest.h>

#include "test_portal_common.h"

namespace pf::test {
namespace {

struct LongCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const LongCase &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int mutationsPerPixel, maxDepth;
};

class LongPortalConvergence : public ::testing::TestWithParam<LongCase> {};

TEST_P(LongPortalConvergence, AgreesWithBDPTAndWithoutPortal) {
    expectPortalConvergence(GetParam().scene, longConvergenceSetup(GetParam().mutationsPerPixel, GetParam().maxDepth),
                            32 * 32 * 64);
}

// The box, lit through its small opening only, needs more mutations per pixel for the same error.
INSTANTIATE_TEST_SUITE_P(Scenes, LongPortalConvergence,
                         ::testing::Values(LongCase{"portal-toy", 1024, 5}, LongCase{"portal-box", 4096, 3},
                                           LongCase{"cornell-box-portal", 1024, 5}),
                         [](const auto &info) { return gtestName(info.param.scene); });

}  // namespace
}  // namespace pf::test
