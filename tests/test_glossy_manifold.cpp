// The glossy extension of the manifold perturbation (offset manifolds, ALGORITHMS.md §6.6; [TR §5.2, A1, eq. 12])
// on GLOSSY SPHERES (scenes/glossy-spheres: a rough glass and a rough gold sphere on a diffuse floor): MEPT, whose
// proposals walk glossy vertices as specular ones, agrees with BDPT (block means of independent renders,
// ALGORITHMS.md §9.1). Such renders only see large errors: they do not tell the offset Jacobian J from J^4
// (tried by hand), which test_detailed_balance.cpp's flux test (GlossyFlux) does at 12 standard errors, next to
// its proposal-by-proposal checks of the density. The Table 1 statistics with and without the extension are
// printed (manifoldGlossyAngle = 0 treats every glossy vertex as non-specular). The longer render comparison is
// in test_long_manifold.cpp.
#include <gtest/gtest.h>

#include "render/normalizer.h"
#include "support/chain_util.h"
#include "test_mlt_common.h"

namespace pf::test {
namespace {

// MEPT alone (every path left to the chains) with the default dtheta of 1 degree: 9 comparisons at 4.5
// standard errors of a Student t with 15 degrees of freedom.
TEST(GlossyManifold, MEPTAgreesWithBDPT) {
    ConvergenceSetup s;
    s.budget = 24;
    expectSingleMutationConvergence("glossy-spheres", MutationType::Manifold, s);
}

// The manifold perturbation's counters over the chain tasks of one MEPT render of glossy-spheres.
struct Statistics {
    MutationCount manifold;
    ChainCounters counters;
    double value(const std::string &name) { return counter(counters, name).value; }
};

Statistics meptStatistics(const std::string &glossyAngle) {
    auto scene = loadMLTTestScene("glossy-spheres", 16, 8);
    const auto integrator = makeTestIntegrator(
        *scene, "mept", {{"directSamples", "-1"}, {"chainLength", "50"}, {"manifoldGlossyAngle", glossyAngle}});
    const ChainStatistics chains = chainStatistics(*scene, *integrator, 8);
    Statistics stats;
    stats.counters = chains.counters;
    for (const MutationCount &c : chains.counts)
        if (c.name == "manifold") stats.manifold = c;
    const double walks = stats.value("manifoldWalks");
    std::printf(
        "glossy-spheres mept, manifoldGlossyAngle %s: %llu proposals, %.1f%% accepted, %.0f glossy vertices "
        "walked as specular, %.0f walks, %.1f%% converged, %.2f Newton iterations, mean chain %.2f, max %.0f, "
        "%.0f reverse walks, %.0f non-reversible\n",
        glossyAngle.c_str(), static_cast<unsigned long long>(stats.manifold.proposed),
        100.0 * static_cast<double>(stats.manifold.accepted) / static_cast<double>(stats.manifold.proposed),
        stats.value("manifoldGlossySpecular"), walks, 100 * stats.value("manifoldWalksConverged") / walks,
        stats.value("manifoldNewtonIterations") / walks, stats.value("manifoldChainVertices") / walks,
        stats.value("manifoldChainVerticesMax"), stats.value("manifoldReverseWalks"),
        stats.value("manifoldNonReversible"));
    return stats;
}

// With the extension, glossy vertices join chains and the walks through them converge and come back; without
// it (dtheta = 0) none does and no chain is walked, since the scene has no ideal specular surface.
TEST(GlossyManifold, TableOneStatistics) {
    Statistics on = meptStatistics("1"), off = meptStatistics("0");
    EXPECT_GT(on.value("manifoldGlossySpecular"), 100);
    ASSERT_GT(on.value("manifoldWalks"), 100);
    EXPECT_GT(on.value("manifoldWalksConverged") / on.value("manifoldWalks"), 0.8);
    EXPECT_LT(on.value("manifoldNonReversible"), 0.05 * on.value("manifoldReverseWalks") + 1);
    EXPECT_GT(on.manifold.accepted, on.manifold.proposed / 10);
    EXPECT_EQ(off.value("manifoldGlossySpecular"), 0);
    EXPECT_EQ(off.value("manifoldWalks"), 0);
    EXPECT_GT(off.manifold.accepted, off.manifold.proposed / 10);
}

TEST(GlossyManifold, AngleParameter) {
    auto scene = loadMLTTestScene("glossy-spheres", 8, 4);
    for (const std::string type : {"mept", "memlt", "erpt", "mlt"}) {
        EXPECT_NO_THROW(makeTestIntegrator(*scene, type, {{"manifoldGlossyAngle", "2.5"}}));
        for (const std::string bad : {"-1", "180"}) try {
                makeTestIntegrator(*scene, type, {{"manifoldGlossyAngle", bad}});
                ADD_FAILURE() << type << " accepted manifoldGlossyAngle = " << bad;
            } catch (const SceneError &e) {
                EXPECT_NE(std::string(e.what()).find("manifoldGlossyAngle"), std::string::npos) << e.what();
            }
    }
}

}  // namespace
}  // namespace pf::test
