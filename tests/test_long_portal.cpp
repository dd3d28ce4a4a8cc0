// The long version of test_portal's comparison (CTest label "long"): mlt with the portal perturbation against
// BDPT and against mlt without it on the three portal scenes at 32 x 32, paths of up to 5 edges, 32 renders.
#include <gtest/gtest.h>

#include "test_portal_common.h"

namespace pf::test {
namespace {

class LongPortalConvergence : public ::testing::TestWithParam<std::string> {};

TEST_P(LongPortalConvergence, AgreesWithBDPTAndWithoutPortal) {
    expectPortalConvergence(GetParam(), longConvergenceSetup(1024, 5), 32 * 32 * 64);
}

INSTANTIATE_TEST_SUITE_P(Scenes, LongPortalConvergence,
                         ::testing::Values("portal-toy", "portal-box", "cornell-box-portal"),
                         [](const auto &info) { return gtestName(info.param); });

}  // namespace
}  // namespace pf::test
