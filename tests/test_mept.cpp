// Manifold exploration path tracing and MLT (`mept`, `memlt`; [TR §8]; ALGORITHMS.md §5.4, §6.5): both agree
// with a BDPT reference on scenes without and with specular chains (block means of independent renders,
// ALGORITHMS.md §9.1), the manifold perturbation is accepted often enough to have shown a bias, and the
// Table 1 statistics reach the chain counters. Bursts from weighted seeds stay unbiased with any transition
// rule that keeps the target distribution (§5.2), so a wrong T ratio of the manifold perturbation, a missing
// measure conversion through a specular chain or an accepted non-reversible walk shows as a biased image.
// Short versions; test_long_manifold.cpp has larger images and more runs.
#include <gtest/gtest.h>

#include "integrators/erpt.h"
#include "integrators/lambda_tuning.h"
#include "path/manifold_perturbation.h"
#include "support/chain_util.h"
#include "test_mlt_common.h"
#include "test_path_helpers.h"

namespace pf::test {
namespace {

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int budget;        // seeds per pixel (mept) or mutations per pixel (memlt)
    int res = 16;      // image size
    int maxDepth = 0;  // longest paths (0: the scene's)
    int chains = 1;    // mept's numChains: bursts per pixel on average
};

class MEPTConvergence : public ::testing::TestWithParam<Case> {};

// MEPT: ERPT's bursts with the manifold perturbation alone (Mitsuba's erpt with manifoldPerturbation = true
// and Veach's perturbations off, which is what `mept` is), every path left to the chains; 13 comparisons per
// case (4 blocks of 8 x 8 pixels, 3 channels, the whole image) at 4.5 standard errors of a Student t with 15
// degrees of freedom. The references' own standard errors are a few tenths of a percent, against the
// chains' few percent.
//
// Budget: a seed launches chains in proportion to its weight (ALGORITHMS.md §5.3), about numChains per pixel
// whatever the seeds per pixel, so the bursts' noise falls with numChains and the seeding's with the seeds.
// Where the bursts dominate, more seeds do not help: ring-caustic's median block error was 4.5% and 4.8% at
// 16 and 32 seeds per pixel with one chain, 2.1% at 8 seeds with 4 chains (from 32 seeds and one chain
// to 8 and 4: cornell-box 4.6% -> 1.9%, veach-bidir 4.9% -> 1.9%, in less time). The pool's error comes from its few
// caustic seeds instead (3.5% at 32 seeds and one chain, 4.8% at 8 seeds and 4 chains).
TEST_P(MEPTConvergence, AgreesWithBDPT) {
    ConvergenceSetup s;
    s.res = GetParam().res;
    s.budget = GetParam().budget;
    s.maxDepth = GetParam().maxDepth;
    expectSingleMutationConvergence(GetParam().scene, MutationType::Manifold, s,
                                    {{"numChains", std::to_string(GetParam().chains) + ".0"}});
}

// cornell-box: only diffuse chains (the perturbation moves one vertex, no walk); veach-bidir: light through
// glass; the pool seen from above: L S D S E, two chains through Dirac refractions; ring-caustic: a smooth
// gold ring's caustic E D S L (block 1, the upper right quarter), whose camera-side moves walk the
// reflection back to the light, and the ring reflecting the lit floor (E S D L).
//
// ring-caustic stops at 3 edges, where BDPT samples every path well. At 4 edges comes E S D S L (the ring
// reflecting a caustic it casts on the floor), which only BDPT's s = 0 strategy samples, by hitting the tiny
// light: 3 times in the 2.4 million samples drawn while writing these tests, each worth about 4 * 10^4
// times a sample's mean (so perhaps 5% of the image, most of it in a few pixels). Neither the reference nor
// the chains' seeding resolves it at these budgets: with unbounded depth, one of 40 renders of 8192 samples
// was 5.7 times as bright as the others (the path had 4 edges: gone at maxDepth 3, unchanged at 4 to 8),
// and at 32 x 32 the long tests' 32 renders came out 9% bright with a 10% standard error.
INSTANTIATE_TEST_SUITE_P(Scenes, MEPTConvergence,
                         ::testing::Values(Case{"cornell-box", 8, 16, 0, 4}, Case{"veach-bidir", 8, 16, 0, 4},
                                           Case{"pool", 32}, Case{"ring-caustic", 8, 16, 3, 4}),
                         [](const auto &info) { return gtestName(info.param.scene); });

// The same under a wall-time budget of one second per render (`render --time`), on the scenes the
// interleaving of passes and the stopping rule must not bias: whole passes while the clock allows.
class MEPTTimeBudget : public ::testing::TestWithParam<Case> {};

TEST_P(MEPTTimeBudget, AgreesWithBDPT) {
    const Case &c = GetParam();
    ConvergenceSetup s = timeBudgetSetup(1.0, c.maxDepth);
    s.budget = c.budget;  // the scene's sampleCount, which bounds the rounds (numChains) a time budget plans
    auto params = singleMutation(MutationType::Manifold);
    params.emplace_back("numChains", std::to_string(c.chains) + ".0");
    expectConvergence(c.scene, "erpt", params, s, c.scene + " mept --time 1");
}

INSTANTIATE_TEST_SUITE_P(Scenes, MEPTTimeBudget,
                         ::testing::Values(Case{"cornell-box", 8, 16, 0, 4}, Case{"veach-bidir", 8, 16, 0, 4},
                                           Case{"ring-caustic", 8, 16, 3, 4}),
                         [](const auto &info) { return gtestName(info.param.scene); });

// lambda = "auto" (integrators/lambda_tuning.h): the pilot's λ depends only on the job seed, lies where the
// manifold perturbation's acceptance is near the target, reaches the chain tasks, and its renders agree with
// BDPT like a hand-set λ's.
TEST(AutoLambda, DeterministicNearTheTargetAndUnbiased) {
    for (const std::string name : {"veach-bidir", "ring-caustic"}) {
        auto scene = loadMLTTestScene(name, 16, 8);
        const int maxDepth = name == "ring-caustic" ? 3 : 0;
        const auto params = withMaxDepth(
            {{"directSamples", "-1"}, {"lambda", "auto"}, {"numChains", "4.0"}, {"chainLength", "100"}}, maxDepth);
        const auto integrator = makeTestIntegrator(*scene, "mept", params);
        const auto &chains = dynamic_cast<const ChainIntegrator &>(*integrator);
        const SeedingTask pilot = chains.seedingTasks(*scene).at(0);
        const double lambda = chains.runSeeding(*scene, 8, 11, pilot).tuning.lambda;
        EXPECT_EQ(chains.runSeeding(*scene, 8, 11, pilot).tuning.lambda, lambda) << "the same seed, another λ";
        EXPECT_NE(chains.runSeeding(*scene, 8, 12, pilot).tuning.lambda, lambda) << "λ ignores the seed";
        ASSERT_GT(lambda, 1);
        ASSERT_LT(lambda, 1e5);
        const Normalizer normalizer = seedChains(*scene, chains, 11);
        EXPECT_EQ(normalizer.tuning().lambda, lambda);
        const ChainTask task = chains.chainTask(*scene, normalizer, 11, 8, 0);
        EXPECT_EQ(task.tuning.lambda, lambda);
        // A render's chains (chainStatistics seeds with 3) accept near the target.
        auto [counts, counters] = chainStatistics(*scene, *integrator, 8);
        const double acceptance = static_cast<double>(counts[0].accepted) / static_cast<double>(counts[0].proposed);
        std::printf("%s mept lambda=auto: lambda %.1f, acceptance %.1f%% (target %.0f%%)\n", name.c_str(), lambda,
                    100 * acceptance, 100 * kLambdaTargetAcceptance);
        EXPECT_NEAR(acceptance, kLambdaTargetAcceptance, 0.12);
        EXPECT_EQ(counter(counters, "lambda").value, chains.runSeeding(*scene, 8, 3, pilot).tuning.lambda);  // its seed
        ConvergenceSetup s;
        s.budget = 8;
        s.maxDepth = maxDepth;
        expectConvergence(name, "erpt", singleMutationWith(MutationType::Manifold, params), s,
                          name + " mept lambda=auto");
    }
}

class MEMLTConvergence : public ::testing::TestWithParam<Case> {};

// MEMLT: long chains with the bidirectional mutation and the manifold perturbation, set up as test_mlt's
// MLT cases (a seeding pool of 8 samples per pixel, 16 renders, 4.5 standard errors of a Student t with 15
// degrees of freedom); 28 comparisons at 24 x 24, 13 at 16 x 16.
TEST_P(MEMLTConvergence, AgreesWithBDPT) {
    ConvergenceSetup s;
    s.res = GetParam().res;
    s.budget = GetParam().budget;
    s.maxDepth = GetParam().maxDepth;
    s.referenceSpp = 32;
    s.maxMedianError = 0.045;
    s.maxImageError = 0.02;
    expectConvergence(GetParam().scene, "memlt",
                      {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(s.res * s.res * 8)}}, s,
                      GetParam().scene + " memlt");
}

// A render's chains are 2^14 mutations long (chainTaskMutations), so the budget sets their number: at
// 16 x 16, 4 per render at 256 mutations per pixel. Regions the bidirectional mutation rarely reaches then
// come out of few chains, and the block means' spread over renders understates their error (slow mixing,
// ALGORITHMS.md §5.4: on ring-caustic at unbounded depth and 256 mutations per pixel, a 4 x 4 block of the
// ring's outer wall came out 6% dark at 3.7 standard errors over 64 renders, and within 1% at 1024); so
// ring-caustic runs 8 chains per render. Its depth is limited as for MEPT above.
INSTANTIATE_TEST_SUITE_P(Scenes, MEMLTConvergence,
                         ::testing::Values(Case{"cornell-box", 64, 24}, Case{"veach-bidir", 256},
                                           Case{"ring-caustic", 512, 16, 3}),
                         [](const auto &info) { return gtestName(info.param.scene); });

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
    // The medium-distance perturbation comes with the manifold perturbation (it applies to paths through media).
    EXPECT_EQ(names("mept", {}), (std::vector<std::string>{"manifold", "mediumDistance", "none"}));
    EXPECT_EQ(names("memlt", {}), (std::vector<std::string>{"bidirectional", "manifold", "mediumDistance", "none"}));
    EXPECT_EQ(names("mept", {{"mediumDistancePerturbation", "false"}}), (std::vector<std::string>{"manifold", "none"}));
    // Reachable through Mitsuba's parameters on erpt and mlt too.
    EXPECT_EQ(names("erpt", {{"manifoldPerturbation", "true"}, {"lensPerturbation", "false"}}),
              (std::vector<std::string>{"caustic", "multiChain", "manifold", "mediumDistance", "none"}));
    EXPECT_EQ(names("mlt", {{"manifoldPerturbation", "true"}, {"lensSubpathMutation", "false"}}),
              (std::vector<std::string>{"bidirectional", "lens", "caustic", "multiChain", "manifold", "mediumDistance",
                                        "none"}));
    EXPECT_EQ(names("erpt", {}), (std::vector<std::string>{"lens", "caustic", "multiChain", "none"}));
    EXPECT_NO_THROW(makeTestIntegrator(*scene, "mept", {{"lambda", "90.0"}, {"probFactor", "90.0"}}));
    EXPECT_NO_THROW(makeTestIntegrator(*scene, "mept", {{"lambda", "auto"}}));
    for (const std::string type : {"mept", "memlt"}) {
        try {
            makeTestIntegrator(*scene, type, {{"lambda", "0.0"}});
            ADD_FAILURE() << type << " accepted lambda = 0";
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("lambda"), std::string::npos) << e.what();
        }
        try {
            makeTestIntegrator(*scene, type, {{"lambda", type == "mept" ? "automatic" : "auto"}});
            ADD_FAILURE() << type << " accepted a lambda it cannot tune";
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
    auto [counts, counters] = chainStatistics(*scene, *integrator, 8);
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

// Medium vertices join chains in glass-egg's forward-scattering medium (§6.7) and are counted (Table 1), and
// mediumChains = false keeps them out.
TEST(ManifoldExploration, MediumVerticesInChains) {
    auto scene = loadMLTTestScene("glass-egg", 16, 8);
    for (const bool on : {true, false}) {
        const auto integrator = makeTestIntegrator(*scene, "mept",
                                                   {{"directSamples", "-1"},
                                                    {"chainLength", "50"},
                                                    {"maxDepth", "6"},
                                                    {"mediumChains", on ? "true" : "false"},
                                                    {"mediumDistancePerturbation", "false"}});
        auto [counts, counters] = chainStatistics(*scene, *integrator, 8);
        const double media = counter(counters, "manifoldMediumVertices").value,
                     walks = counter(counters, "manifoldWalks").value;
        std::printf(
            "glass-egg mept, mediumChains %s: %.0f proposals, %.0f accepted, %.0f walks, %.0f medium vertices "
            "walked in chains\n",
            on ? "on" : "off", static_cast<double>(counts[0].proposed), static_cast<double>(counts[0].accepted), walks,
            media);
        if (on) {
            EXPECT_GT(media, 20);
            EXPECT_GT(counts[0].accepted, counts[0].proposed / 10);
        } else {
            EXPECT_EQ(media, 0);
        }
    }
}

// A path that the camera sees through glass into a medium, E S M .. (glass-egg's glow), moves on the film only if
// its medium vertex can be x_b, the vertex that moves: every other source's move ends at the sensor through a
// specular chain, which no walk can move (§6.7). Before medium vertices could be x_b, no proposal from such a
// path moved its raster position (without medium chains, where classification cannot carry the move past the
// medium vertex), and MEPT's bursts from them deposited all their energy in one pixel: bench_manifold's relMSE of
// 0.95 on the egg.
TEST(ManifoldExploration, PathsSeenThroughGlassInAMediumMoveOnTheFilm) {
    auto scene = loadMLTTestScene("glass-egg", 16, 4);
    const ManifoldPerturbation mutation(*scene, 50.0, kPi / 180, false);
    int paths = 0, proposals = 0, moved = 0;
    for (const MutablePath &x : bdptPaths(*scene, 3000, 16)) {
        const int n = x.length();
        int first = n - 2;  // the first non-specular vertex from the camera
        while (first > 0 && !isNonSpecular(x.vertex(first))) --first;
        if (first == n - 2 || x.vertex(first).type != VertexType::Medium || paths == 40) continue;
        ++paths;
        for (uint64_t k = 0; k < 8; ++k) {
            IndependentSampler sampler(5, static_cast<uint64_t>(paths), k);
            MutablePath y;
            MutationRecord record;
            if (!mutation.sample(*scene, sampler, x, y, record) || !(chainContribution(*scene, y).luminance() > 0))
                continue;
            ++proposals;
            moved += std::hypot(y.raster().x - x.raster().x, y.raster().y - x.raster().y) > 1e-3;
        }
    }
    std::printf("glass-egg: %d paths E S .. M .., %d proposals, %d moved on the film\n", paths, proposals, moved);
    ASSERT_GE(paths, 20);
    // Only the sources whose move reaches the sensor change the film position: 86 of 223 proposals from 40
    // paths (0 of 192 before).
    EXPECT_GE(moved, paths) << "paths seen through glass in a medium stay in their pixel";
}

// A time budget is spent in whole passes, so their size is the step by which a timed render misses its
// budget: with the manifold perturbation (1.7-3.2 times dearer per mutation than Veach's perturbations) the
// default pass holds kManifoldPassMutations, not erpt's 2^20, at the scene's own size (1024²; a time budget plans
// one round there, numChains being 1) as at 64². An explicit passMutations still rules.
TEST(MEPTPlan, ManifoldPassesAreSmallerThanErpts) {
    const auto passMutations = [](const Scene &scene, const std::string &name,
                                  const std::vector<std::pair<std::string, std::string>> &params) {
        const auto integrator = makeTestIntegrator(scene, name, params);
        const BurstPlan p = dynamic_cast<const ERPT &>(*integrator).plan(scene, 0);
        return static_cast<double>(p.pixels) * p.chainsPerPixel * 100.0 / static_cast<double>(p.interleave);
    };
    for (const int res : {1024, 64}) {
        auto scene = loadMLTTestScene("volumetric-caustic-small", res, 64);
        const double mept = passMutations(*scene, "mept", {}), erpt = passMutations(*scene, "erpt", {});
        EXPECT_LE(mept, static_cast<double>(kManifoldPassMutations)) << res;
        EXPECT_LE(passMutations(*scene, "erpt", {{"manifoldPerturbation", "true"}}),
                  static_cast<double>(kManifoldPassMutations))
            << res;
        EXPECT_LE(erpt, static_cast<double>(kDefaultPassMutations)) << res;
        if (res == 1024) {
            EXPECT_GT(mept, kManifoldPassMutations / 2.0);  // passes no smaller than they need be
            EXPECT_GT(erpt, static_cast<double>(kManifoldPassMutations)) << "erpt's passes stay as they were";
            EXPECT_GT(passMutations(*scene, "mept", {{"passMutations", "1048576"}}),
                      static_cast<double>(kManifoldPassMutations));
        }
    }
}

}  // namespace
}  // namespace pf::test
