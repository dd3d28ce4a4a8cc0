// Manifold exploration path tracing and MLT (`mept`, `memlt`; [TR §8]; ALGORITHMS.md §5.4, §6.5): both agree
// with a BDPT reference on scenes without and with specular chains (block means of independent renders,
// ALGORITHMS.md §9.1), the manifold perturbation is accepted often enough to have shown a bias, and the
// Table 1 statistics reach the chain counters. Bursts from weighted seeds stay unbiased with any transition
// rule that keeps the target distribution (§5.2), so a wrong T ratio of the manifold perturbation, a missing
// measure conversion through a specular chain or an accepted non-reversible walk shows as a biased image.
// Short versions; test_long_manifold.cpp has larger images and more runs.
#include <gtest/gtest.h>

#include "integrators/erpt.h"
#include "render/normalizer.h"
#include "support/chain_util.h"
#include "test_mlt_common.h"

namespace pf::test {
namespace {

std::string testName(std::string n) {
    std::replace(n.begin(), n.end(), '-', '_');
    return n;
}

struct Case {
    std::string scene;
    int budget;  // seeds per pixel (mept) or mutations per pixel (memlt)
};

class MEPTConvergence : public ::testing::TestWithParam<Case> {};

// MEPT: ERPT's bursts with the manifold perturbation alone (Mitsuba's erpt with manifoldPerturbation = true
// and Veach's perturbations off, which is what `mept` is), every path left to the chains; 9 comparisons per
// case at 4.5 standard errors of a Student t with 15 degrees of freedom.
TEST_P(MEPTConvergence, AgreesWithBDPT) {
    ConvergenceSetup s;
    s.budget = GetParam().budget;
    expectSingleMutationConvergence(GetParam().scene, MutationType::Manifold, s);
}

// cornell-box: only diffuse chains (the perturbation moves one vertex, no walk); veach-bidir: light through
// glass; the pool seen from above: L S D S E, two chains through Dirac refractions. ring-caustic (whose
// camera-side moves walk a reflection back to the light) is in test_long_manifold: at this size its few
// caustic seeds make both images too noisy for the comparison to mean anything.
INSTANTIATE_TEST_SUITE_P(Scenes, MEPTConvergence,
                         ::testing::Values(Case{"cornell-box", 32}, Case{"veach-bidir", 32}, Case{"pool", 32}),
                         [](const auto &info) { return testName(info.param.scene); });

class MEMLTConvergence : public ::testing::TestWithParam<Case> {};

// MEMLT: long chains with the bidirectional mutation and the manifold perturbation, set up as test_mlt's
// MLT cases (24 x 24, a small seeding pool; 37 comparisons per case).
TEST_P(MEMLTConvergence, AgreesWithBDPT) {
    ConvergenceSetup s;
    s.res = 24;
    s.budget = GetParam().budget;
    s.referenceSpp = 32;
    s.maxMedianError = 0.045;
    s.maxImageError = 0.02;
    expectConvergence(GetParam().scene, "memlt",
                      {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(24 * 24 * 8)}}, s,
                      GetParam().scene + " memlt");
}

INSTANTIATE_TEST_SUITE_P(Scenes, MEMLTConvergence, ::testing::Values(Case{"cornell-box", 64}),
                         [](const auto &info) { return testName(info.param.scene); });

TEST(ManifoldExploration, IntegratorsAndParameters) {
    auto scene = loadMLTTestScene("cornell-box", 8, 4);
    const auto names = [&](const std::string &type, const std::vector<std::pair<std::string, std::string>> &params) {
        std::vector<std::string> list;
        const auto integrator = makeTestIntegrator(*scene, type, params);
        for (const MutationCount &c : dynamic_cast<const ChainIntegrator &>(*integrator).mutationTypes())
            list.push_back(c.name);
        EXPECT_EQ(integrator->name(), type);
        return list;
    };
    EXPECT_EQ(names("mept", {}), (std::vector<std::string>{"manifold", "none"}));
    EXPECT_EQ(names("memlt", {}), (std::vector<std::string>{"bidirectional", "manifold", "none"}));
    // Reachable through Mitsuba's parameters on erpt and mlt too.
    EXPECT_EQ(names("erpt", {{"manifoldPerturbation", "true"}, {"lensPerturbation", "false"}}),
              (std::vector<std::string>{"caustic", "multiChain", "manifold", "none"}));
    EXPECT_EQ(names("mlt", {{"manifoldPerturbation", "true"}, {"lensSubpathMutation", "false"}}),
              (std::vector<std::string>{"bidirectional", "lens", "caustic", "multiChain", "manifold", "none"}));
    EXPECT_NO_THROW(makeTestIntegrator(*scene, "mept", {{"lambda", "90.0"}, {"probFactor", "90.0"}}));
    for (const std::string type : {"mept", "memlt"}) {
        try {
            makeTestIntegrator(*scene, type, {{"lambda", "0.0"}});
            ADD_FAILURE() << type << " accepted lambda = 0";
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("lambda"), std::string::npos) << e.what();
        }
    }
}

// Table 1's statistics (ALGORITHMS.md §5.5) on ring-caustic, whose camera-side moves walk a reflection chain:
// walks happen, most converge in a few Newton iterations, chains have one specular vertex, few walks fail
// to come back.
TEST(ManifoldExploration, WalkStatistics) {
    auto scene = loadMLTTestScene("ring-caustic", 16, 8);
    const auto integrator = makeTestIntegrator(*scene, "mept", {{"directSamples", "-1"}, {"chainLength", "50"}});
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*integrator);
    const Normalizer normalizer = seedChains(*scene, chains, 3);
    ChainCounters counters;
    MutationCounts counts;
    for (uint64_t k = 0; k < chains.chainTaskCount(*scene, 8); ++k) {
        const ChainResult r = runChainTask(*scene, chains, 3, chains.chainTask(*scene, normalizer, 3, 8, k));
        addCounters(counters, r.counters);
        addCounts(counts, r.counts);
    }
    const auto value = [&](const std::string &name) { return counter(counters, name).value; };
    const double walks = value("manifoldWalks"), converged = value("manifoldWalksConverged");
    std::printf(
        "ring-caustic mept: %.0f proposals, %.0f accepted, %.0f walks, %.1f%% converged, %.2f Newton "
        "iterations, mean chain %.2f, max %.0f, %.0f reverse walks, %.0f non-reversible\n",
        static_cast<double>(counts[0].proposed), static_cast<double>(counts[0].accepted), walks,
        100 * converged / walks, value("manifoldNewtonIterations") / walks, value("manifoldChainVertices") / walks,
        value("manifoldChainVerticesMax"), value("manifoldReverseWalks"), value("manifoldNonReversible"));
    ASSERT_GT(walks, 100);
    EXPECT_GT(converged / walks, 0.8);
    EXPECT_GT(value("manifoldNewtonIterations") / walks, 0.5);
    EXPECT_LT(value("manifoldNewtonIterations") / walks, 6);
    EXPECT_GE(value("manifoldChainVerticesMax"), 1);
    EXPECT_LT(value("manifoldNonReversible"), 0.05 * value("manifoldReverseWalks") + 1);
    EXPECT_GT(counts[0].accepted, counts[0].proposed / 10);
}

}  // namespace
}  // namespace pf::test
