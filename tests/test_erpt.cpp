// Energy redistribution path tracing (`erpt`, Cline et al. 2005; ALGORITHMS.md §5): convergence to a BDPT
// reference, the allocation of bursts to seed paths (§5.3), the parameters, and, through bursts, each of
// Veach's mutations on its own. Bursts from properly weighted seeds stay unbiased with any transition rule
// that keeps the target's distribution, ergodic or not (§5.2), so a mutation with a wrong T ratio shows up
// as a biased image, whichever mutation it is. Comparisons are block means of images rendered with
// independent seeds (ALGORITHMS.md §9.1: MCMC errors from independent runs, not from per-sample variance).
// Short versions; test_long_erpt.cpp has larger images, more runs and more scenes.
#include <gtest/gtest.h>

#include <map>
#include <tuple>

#include "integrators/erpt.h"
#include "render/normalizer.h"
#include "test_mlt_common.h"

namespace pf::test {
namespace {

constexpr int kRes = 16;

class ERPTConvergence : public ::testing::TestWithParam<std::string> {};

// Mitsuba's perturbations (lens, caustic and multi-chain), every path left to the chains, bursts of 400
// mutations (short bursts leave more of the noise of picking a few seed paths per pixel).
TEST_P(ERPTConvergence, AgreesWithBDPT) {
    expectConvergence(GetParam(), "erpt", {{"directSamples", "-1"}, {"chainLength", "400"}}, ConvergenceSetup{},
                      GetParam() + " erpt");
}

INSTANTIATE_TEST_SUITE_P(Scenes, ERPTConvergence, ::testing::Values("cornell-box", "veach-mis", "veach-bidir"),
                         [](const auto &info) { return gtestName(info.param); });

struct Case {
    std::string scene;
    MutationType type;
};

class SingleMutationBursts : public ::testing::TestWithParam<Case> {};

TEST_P(SingleMutationBursts, AgreeWithBDPT) {
    expectSingleMutationConvergence(GetParam().scene, GetParam().type, ConvergenceSetup{});
}

// Each mutation alone: the bidirectional and lens subpath mutations and the lens and caustic perturbations
// on diffuse paths, the caustic perturbation through glass and water (Dirac refractions, whose densities
// are converted to the canonical measure), and the multi-chain perturbation in the pool.
INSTANTIATE_TEST_SUITE_P(
    Scenes, SingleMutationBursts,
    ::testing::Values(Case{"cornell-box", MutationType::Bidirectional}, Case{"cornell-box", MutationType::LensSubpath},
                      Case{"cornell-box", MutationType::Lens}, Case{"cornell-box", MutationType::Caustic},
                      Case{"veach-bidir", MutationType::Caustic}, Case{"pool", MutationType::MultiChain},
                      Case{"pool-underwater", MutationType::Caustic}),
    [](const auto &info) { return gtestName(info.param.scene + "_" + mutationName(info.param.type)); });

// §5.3, Cline's bookkeeping: a seed of weight w starts floor(nu + U) chains, nu = numChains w / W (capped at
// maxChains), each of weight w / nu, so that its bursts carry w in expectation; on average numChains chains
// per pixel.
TEST(ERPTChains, EnergyPerSeed) {
    auto scene = loadMLTTestScene("cornell-box", kRes, 8);
    for (const bool capped : {false, true}) {
        const auto integrator = makeTestIntegrator(
            *scene, "erpt", {{"numChains", "2.5"}, {"maxChains", capped ? "3" : "0"}, {"chainLength", "7"}});
        const auto &erpt = dynamic_cast<const ERPT &>(*integrator);
        std::vector<SeedingResult> seeds;
        for (const SeedingTask &t : seedingTasks(*scene))
            seeds.push_back(runSeedingTask(*scene, erpt.seeding(*scene), 5, t));
        const Normalizer normalizer(std::move(seeds));
        const double mean = normalizer.luminance() / (kRes * kRes);
        std::map<std::tuple<uint64_t, uint64_t, int, int>, std::vector<double>> chains;
        for (uint64_t k = 0; k < erpt.chainTaskCount(*scene, 8); ++k) {
            const ChainTask task = erpt.chainTask(*scene, normalizer, 5, 8, k);
            EXPECT_EQ(task.mutations, 7u);
            for (const ChainSeed &s : task.seeds)
                chains[{s.record.pixel, s.record.sampleIndex, s.record.s, s.record.t}].push_back(s.weight);
        }
        double expected = 0, variance = 0;
        size_t total = 0, matched = 0;
        for (const auto &[record, weights] : chains) total += weights.size();
        for (const SeedCandidate &c : normalizer.candidates()) {
            const double nu = erpt.expectedChains(c.weight, mean);
            EXPECT_NEAR(nu, capped ? std::min(3.0, 2.5 * c.weight / mean) : 2.5 * c.weight / mean, 1e-12 * nu);
            const auto it = chains.find({c.record.pixel, c.record.sampleIndex, c.record.s, c.record.t});
            const size_t count = it == chains.end() ? 0 : it->second.size();
            EXPECT_TRUE(count == static_cast<size_t>(std::floor(nu)) ||
                        count == static_cast<size_t>(std::floor(nu)) + 1)
                << count << " chains for nu = " << nu;
            if (it != chains.end()) {
                for (const double weight : it->second) EXPECT_NEAR(weight, c.weight / nu, 1e-12 * c.weight / nu);
            }
            expected += nu;
            variance += (nu - std::floor(nu)) * (1 - (nu - std::floor(nu)));
            matched += count;
        }
        EXPECT_EQ(matched, total) << "chains start only from seeding candidates";
        // The rounding is unbiased: the total lies within 4 standard deviations of its expectation.
        EXPECT_NEAR(static_cast<double>(total), expected, 4 * std::sqrt(variance));
        if (!capped) {
            EXPECT_NEAR(expected, 2.5 * kRes * kRes, 1e-9 * expected);
        }
    }
}

TEST(ERPTParameters, MitsubaNamesAndChecks) {
    auto scene = loadMLTTestScene("cornell-box", 8, 4);
    // Mitsuba 0.6's erpt parameters are understood.
    EXPECT_NO_THROW(makeTestIntegrator(*scene, "erpt",
                                       {{"numChains", "1.5"},
                                        {"maxChains", "4"},
                                        {"chainLength", "200"},
                                        {"directSamples", "8"},
                                        {"lensPerturbation", "true"},
                                        {"causticPerturbation", "false"},
                                        {"multiChainPerturbation", "true"},
                                        {"bidirectionalMutation", "false"},
                                        {"manifoldPerturbation", "false"},
                                        {"lambda", "80.0"},
                                        {"rrDepth", "8"}}));
    const auto fails = [&](const std::vector<std::pair<std::string, std::string>> &params, const std::string &what) {
        try {
            makeTestIntegrator(*scene, "erpt", params);
            ADD_FAILURE() << "accepted " << params.front().first;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    fails({{"numChains", "0.0"}}, "numChains");
    fails({{"maxChains", "-1"}}, "maxChains");
    fails({{"chainLength", "0"}}, "chainLength");
    fails({{"lambda", "-1.0"}}, "lambda");
    fails({{"lensPerturbation", "false"}, {"causticPerturbation", "false"}, {"multiChainPerturbation", "false"}},
          "at least one mutation");
    fails({{"chainLenght", "10"}}, "chainLenght");
    // The seeds per pixel are --spp, by default the scene's sampleCount (4 here).
    const auto erpt = makeTestIntegrator(*scene, "erpt", {});
    EXPECT_EQ(dynamic_cast<const ERPT &>(*erpt).seeding(*scene).samplesPerPixel, 4);
    EXPECT_EQ(dynamic_cast<const ERPT &>(*erpt).seeding(*scene, 16).samplesPerPixel, 16);
}

}  // namespace
}  // namespace pf::test
