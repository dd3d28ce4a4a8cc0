// The pilot for the dtheta of medium vertices (integrators/medium_angle_pilot.h): on the egg filled with a
// g = 0.8 medium it measures changes of scattering angle, deterministically for a seed, within a plausible
// range, and smaller for smaller steps (a larger λ); with the dtheta it picks, the manifold perturbation keeps
// detailed balance on the egg's paths (the classification enters T at the source state).
#include <gtest/gtest.h>

#include "core/math.h"
#include "integrators/erpt.h"
#include "integrators/medium_angle_pilot.h"
#include "mcmc/metropolis.h"
#include "path/manifold_perturbation.h"
#include "render/normalizer.h"
#include "render/pilot.h"
#include "test_mlt_common.h"
#include "test_path_helpers.h"

namespace pf::test {
namespace {

constexpr uint64_t kJobSeed = 5;

MediumAnglePilot pilotOn(const Scene &scene, const std::string &lambda) {
    const auto integrator = makeTestIntegrator(scene, "mept", {{"lambda", lambda}, {"luminanceSamples", "4096"}});
    const auto &mept = dynamic_cast<const ERPT &>(*integrator);
    const SeedingResult pilot = runPilot(scene, mept.seeding(scene), kJobSeed, 4096, true);
    return pilotMediumAngle(scene, mept, pilotSeed(kJobSeed), pilot.candidates);
}

TEST(MediumAnglePilot, DeterministicPlausibleAndSmallerForSmallerSteps) {
    auto scene = loadMLTTestScene("glass-egg-largelight", 16, 4);
    const MediumAnglePilot coarse = pilotOn(*scene, "10"), fine = pilotOn(*scene, "300");
    std::printf("dtheta at lambda 10: %.3f deg (%llu changes); at lambda 300: %.3f deg (%llu changes)\n",
                coarse.angle * 180 / kPi, static_cast<unsigned long long>(coarse.changes), fine.angle * 180 / kPi,
                static_cast<unsigned long long>(fine.changes));
    EXPECT_EQ(pilotOn(*scene, "10").angle, coarse.angle) << "the same seed, another dtheta";
    ASSERT_GE(coarse.changes, 100u) << "too few medium vertices moved to measure anything";
    ASSERT_GE(fine.changes, 100u);
    // A vertex's scattering angle changes by at most 180 degrees; a mean near that, or of a float's noise, is a
    // measurement of something else.
    for (const MediumAnglePilot &p : {coarse, fine}) {
        EXPECT_GT(p.angle, 1e-3 * kPi / 180);
        EXPECT_LT(p.angle, kPi / 2);
    }
    EXPECT_GT(coarse.angle, 3 * fine.angle) << "a 30 times larger kernel should turn angles further";
}

// Detailed balance of the manifold perturbation at the pilot's dtheta for media, on the egg's luminance
// pilot paths: pi(x) T(x -> y) a(x -> y) = pi(y) T(y -> x) a(y -> x) for every sampled proposal, with medium
// vertices in chains. At λ = 10, whose dtheta (about 2.6 degrees) puts more of them in chains than λ = 50's
// (about 1 degree, the default's value).
TEST(MediumAnglePilot, DetailedBalanceAtThePilotsAngle) {
    auto scene = loadMLTTestScene("glass-egg-largelight", 16, 4);
    const double angle = pilotOn(*scene, "10").angle;
    const ManifoldPerturbation mutation(*scene, 10.0, kPi / 180, true, angle);
    const auto integrator = makeTestIntegrator(*scene, "mept", {{"luminanceSamples", "4096"}});
    const auto &mept = dynamic_cast<const ERPT &>(*integrator);
    const SeedingResult pilot = runPilot(*scene, mept.seeding(*scene), kJobSeed + 1, 4096, true);
    int proposals = 0, symmetric = 0, mediumChains = 0;
    for (size_t i = 0; i < pilot.candidates.size() && proposals < 400; ++i) {
        MutablePath x;
        mept.bdpt().regenerate(*scene, pilotSeed(kJobSeed + 1), pilot.candidates[i].record,
                               [&](const StrategySample &s) { x = MutablePath(*s.path); });
        if (x.length() == 0 || !mutation.applies(x)) continue;
        const double piX = chainContribution(*scene, x).luminance();
        if (!(piX > 0)) continue;
        for (uint64_t j = 0; j < 8; ++j) {
            IndependentSampler sampler(77, i, j);
            MutablePath y;
            MutationRecord r;
            const bool sampled = mutation.sample(*scene, sampler, x, y, r);
            const double piY = sampled ? chainContribution(*scene, y).luminance() : 0.0;
            if (!(piY > 0)) continue;
            ++proposals;
            const int fixed = r.l == r.source ? r.m : r.l;
            for (int k = std::min(r.source, fixed) + 1; k < std::max(r.source, fixed); ++k)
                mediumChains += k != r.moving && y.vertex(k).type == VertexType::Medium;
            const double txy = mutation.density(*scene, x, y, r), tyx = mutation.density(*scene, y, x, r.reverse());
            ASSERT_GT(txy, 0.0);
            if (!(tyx > 0)) continue;
            ++symmetric;
            // Both sides of detailed balance, as test_mh writes them.
            const double forward = piX * txy * acceptance(piX, {0, piY, txy, tyx, false});
            const double backward = piY * tyx * acceptance(piY, {0, piX, tyx, txy, false});
            EXPECT_NEAR(forward, backward, 1e-12 * std::max(forward, backward)) << "path " << i << " proposal " << j;
        }
    }
    std::printf("pilot dtheta %.3f deg: %d proposals, %d with symmetric support, %d medium vertices in chains\n",
                angle * 180 / kPi, proposals, symmetric, mediumChains);
    EXPECT_GE(symmetric, 50) << "too few proposals to mean anything";
    EXPECT_GE(mediumChains, 10) << "medium vertices should join chains at the pilot's dtheta";
}

// manifoldMediumAngle = "auto": mept's luminance pilot measures dtheta on its own paths (the value pilotMediumAngle
// gives on that pool at the chains' λ), deterministically for a job seed; the normalizer hands it to every chain
// task, and the chains report it in degrees with their statistics. With lambda = "auto" too, dtheta is measured
// at the tuned λ.
TEST(MediumAnglePilot, AutoIsMeasuredByThePilotAndReachesTheChainTasks) {
    auto scene = loadMLTTestScene("glass-egg-largelight", 16, 4);
    const auto make = [&](const std::string &lambda) {
        return makeTestIntegrator(
            *scene, "mept",
            {{"manifoldMediumAngle", "auto"}, {"lambda", lambda}, {"luminanceSamples", "4096"}, {"chainLength", "20"}});
    };
    const auto integrator = make("10");
    const auto &mept = dynamic_cast<const ERPT &>(*integrator);
    ASSERT_TRUE(mept.mediumAngleAuto());
    const SeedingTask pilotTask = mept.seedingTasks(*scene).at(0);
    const SeedingResult pilot = mept.runSeeding(*scene, 1, kJobSeed, pilotTask);
    EXPECT_TRUE(pilot.candidates.empty()) << "the pilot ships sums and what it tuned only";
    EXPECT_EQ(pilot.tuning.lambda, 0) << "lambda was set by hand";
    EXPECT_EQ(pilot.tuning.mediumAngle, pilotOn(*scene, "10").angle);
    EXPECT_NE(pilot.tuning.mediumAngle, mept.mediumAngle()) << "the egg's medium vertices should have been measured";
    EXPECT_EQ(mept.runSeeding(*scene, 1, kJobSeed, pilotTask).tuning, pilot.tuning) << "the same seed, another dtheta";

    const Normalizer normalizer({pilot});
    EXPECT_EQ(normalizer.tuning(), pilot.tuning);
    EXPECT_EQ(mept.chainTask(*scene, normalizer, kJobSeed, 1, 0).tuning, pilot.tuning);
    ChainStatistics stats = chainStatistics(*scene, mept, 1);  // seeded with 3
    EXPECT_EQ(counter(stats.counters, "mediumAngle").value,
              mept.runSeeding(*scene, 1, 3, pilotTask).tuning.mediumAngle * 180 / kPi);

    // Both tuned: dtheta is measured at the tuned λ, not at the integrator's 50.
    const auto both = make("auto");
    const auto &tuned = dynamic_cast<const ERPT &>(*both);
    const SeedingResult bothPilot = tuned.runSeeding(*scene, 1, kJobSeed, pilotTask);
    ASSERT_GT(bothPilot.tuning.lambda, 0);
    const SeedingResult pool = runPilot(*scene, tuned.seeding(*scene), kJobSeed, 4096, true);
    EXPECT_EQ(bothPilot.tuning.mediumAngle,
              pilotMediumAngle(*scene, tuned, pilotSeed(kJobSeed), pool.candidates, bothPilot.tuning.lambda).angle);
    std::printf("pilot dtheta %.3f deg at lambda 10; %.3f deg at the tuned lambda %.1f\n",
                pilot.tuning.mediumAngle * 180 / kPi, bothPilot.tuning.mediumAngle * 180 / kPi,
                bothPilot.tuning.lambda);
}

// manifoldMediumAngle: in degrees, by default manifoldGlossyAngle's value; outside [0, 180) an error naming it;
// "auto" for mept only (memlt has no luminance pilot to measure it on).
TEST(MediumAnglePilot, AngleParameter) {
    auto scene = loadMLTTestScene("glass-egg-largelight", 8, 4);
    for (const std::string type : {"mept", "memlt"}) {
        const auto angle = [&](const std::vector<std::pair<std::string, std::string>> &params) {
            const auto integrator = makeTestIntegrator(*scene, type, params);
            return dynamic_cast<const PathSpaceIntegrator &>(*integrator).mediumAngle() * 180 / kPi;
        };
        EXPECT_NEAR(angle({}), 1.0, 1e-12) << type;
        EXPECT_NEAR(angle({{"manifoldGlossyAngle", "3.0"}}), 3.0, 1e-12) << type;
        EXPECT_NEAR(angle({{"manifoldGlossyAngle", "3.0"}, {"manifoldMediumAngle", "2.5"}}), 2.5, 1e-12) << type;
        // The message of the error that `value` raises (empty when it is accepted).
        const auto error = [&](const std::string &value) {
            std::string message;
            try {
                makeTestIntegrator(*scene, type, {{"manifoldMediumAngle", value}});
            } catch (const SceneError &e) {
                message = e.what();
            }
            return message;
        };
        EXPECT_NE(error("-1").find("manifoldMediumAngle"), std::string::npos) << type;
        EXPECT_NE(error("180").find("manifoldMediumAngle"), std::string::npos) << type;
        EXPECT_NE(error("automatic").find("manifoldMediumAngle"), std::string::npos) << type;
        EXPECT_EQ(error("auto").empty(), type == "mept") << type << ": " << error("auto");
    }
}

}  // namespace
}  // namespace pf::test
