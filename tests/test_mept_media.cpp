// Manifold exploration through media ([TR §7]; ALGORITHMS.md §6.7): MEPT and MEMLT with medium vertices in their
// chains (mediumChains, the default), medium x_b and the medium-distance perturbation agree with BDPT and with
// `volpath` on the media scenes (block means of 16 independent renders at 16 x 16, test_mlt_common.h), under
// budgets in samples and under `--time`. Bursts from weighted seeds are unbiased with any transition rule that
// keeps the target (§5.2), so a wrong density of a medium chain, of a medium x_b or of a distance move shows as a
// biased image.
//
// Scenes: ring-caustic-medium (the ring in a g = 0.8 fog; 3 edges, as ring-caustic in test_mept.cpp),
// volumetric-caustic-small (6 edges), and glass-egg with its light 5 times as wide ("-largelight": BDPT finds the
// light seen through the egg only by hitting it) compared as one block, since its 8 x 8 blocks above the floor
// carry 4-8% errors on either side at this budget. volpath finds the caustics through the glass or off the ring,
// and volumetric-caustic-small's light itself (seen through the index-matched front wall), only by hitting the
// small lights: rare, heavy-tailed samples whose spread over 16 renders understates their error (10% low with
// |z| = 14 on volumetric-caustic-small). So volpath is the reference where it resolves the image, single
// scattering in ring-caustic-medium's fog (2 edges: E M L, which MEPT explores with the medium x_b's junction move
// and the distance move), and BDPT elsewhere. test_long_mept_media.cpp: 32 x 32, 32 renders, blocks of 8.
//
// Chains across index-matched boundaries: volumetric-caustic-small's camera sees the gas through the index-matched
// front wall, so a chain with a medium vertex next to the camera crosses it (the held edge from the camera, or the
// walk's last segment). With dtheta = 20 degrees ("_dtheta20") medium vertices join chains often enough for those
// chains to carry a share of the image (bench_manifold's Table 1 "cross" column counts them).
#include <gtest/gtest.h>

#include "test_mept_media_common.h"

namespace pf::test {
namespace {

class MEPTMedia : public ::testing::TestWithParam<MediaCase> {};

TEST_P(MEPTMedia, Agrees) {
    const MediaCase &c = GetParam();
    expectConvergence(c.scene, "erpt", meptParams(c), mediaSetup(c), c.scene + " mept");
}

INSTANTIATE_TEST_SUITE_P(Scenes, MEPTMedia,
                         ::testing::Values(MediaCase{"ring-caustic-medium", 3},
                                           MediaCase{"volumetric-caustic-small", 6},
                                           MediaCase{"volumetric-caustic-small", 6, 8, "bdpt", 8, 4, 20},
                                           MediaCase{"glass-egg-largelight", 6, 16},
                                           MediaCase{"ring-caustic-medium", 2, 8, "volpath"}),
                         [](const auto &info) { return caseName(info.param); });

// Under a wall-time budget of one second per render (`render --time`): whole passes while the clock allows.
TEST(MEPTMediaTimeBudget, AgreesWithBDPT) {
    const MediaCase c{"ring-caustic-medium", 3};
    ConvergenceSetup s = mediaSetup(c, timeBudgetSetup(1.0));
    expectConvergence(c.scene, "erpt", meptParams(c), s, c.scene + " mept --time 1");
}

// MEMLT: the bidirectional mutation and the manifold perturbation (with the distance perturbation), long chains
// from a seeding pool of 8 samples per pixel, as test_mept.cpp's MEMLT cases.
TEST(MEMLTMedia, AgreesWithBDPT) {
    const MediaCase c{"ring-caustic-medium", 3};
    ConvergenceSetup s = mediaSetup(c);
    s.budget = 256;
    s.referenceSpp = 32;
    s.maxMedianError = 0.045;
    s.maxImageError = 0.02;
    expectConvergence(c.scene, "memlt", memltParams(s.res), s, c.scene + " memlt");
}

}  // namespace
}  // namespace pf::test
