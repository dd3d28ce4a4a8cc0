#include "integrators/erpt.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "integrators/lambda_tuning.h"
#include "integrators/medium_angle_pilot.h"
#include "render/normalizer.h"
#include "render/pilot.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The stream of the rounding of chain counts, apart from every other generator of the job.
constexpr uint64_t kChainCountStream = 0xe127ULL;

}  // namespace

ERPT::ERPT(const Properties &props, bool manifoldExploration)
    : PathSpaceIntegrator(
          props, manifoldExploration
                     ? std::vector<MutationType>{MutationType::Manifold}
                     : std::vector<MutationType>{MutationType::Lens, MutationType::Caustic, MutationType::MultiChain}),
      manifoldExploration_(manifoldExploration) {
    numChains_ = props.getFloat("numChains", 1.0);
    maxChains_ = props.getInt("maxChains", 0);
    chainLength_ = props.getInt("chainLength", 100);
    luminanceSamples_ = props.getInt("luminanceSamples", 15000);
    passMutations_ =
        props.getInt("passMutations", usesManifoldPerturbation() ? kManifoldPassMutations : kDefaultPassMutations);
    if (passMutations_ < 1) props.fail("passMutations", "must be at least 1");
    if (luminanceSamples_ < 1) props.fail("luminanceSamples", "must be at least 1");
    if (!(numChains_ > 0) || !std::isfinite(numChains_)) props.fail("numChains", "must be positive");
    if (maxChains_ < 0) props.fail("maxChains", "must be 0 (no cap) or positive");
    if (chainLength_ < 1) props.fail("chainLength", "must be at least 1");
}

SeedingConfig ERPT::seeding(const Scene &, int64_t) const { return seedingWith(1); }

std::vector<SeedingTask> ERPT::seedingTasks(const Scene &) const {
    return {SeedingTask{0, 0, static_cast<uint64_t>(luminanceSamples_)}};
}

int64_t ERPT::timeBudgetPlan(const Scene &scene) const {
    // numChains is positive and finite (checked at construction).
    const double rounds =
        std::min(std::floor(numChains_), static_cast<double>(std::max(1, scene.sensor().sampleCount())));
    return std::max<int64_t>(1, static_cast<int64_t>(rounds));
}

BurstPlan ERPT::plan(const Scene &scene, int64_t spp) const {
    const int64_t rounds = spp > 0 ? spp : timeBudgetPlan(scene);
    return burstPlan(scene, numChains_ / static_cast<double>(rounds), chainLength_, passMutations_);
}

SeedingResult ERPT::runSeeding(const Scene &scene, int64_t, uint64_t seed, const SeedingTask &task) const {
    if (!lambdaAuto() && !mediumAngleAuto()) return runPilot(scene, seeding(scene), seed, task.pilotSamples);
    SeedingResult pilot = runPilot(scene, seeding(scene), seed, task.pilotSamples, true);
    if (lambdaAuto()) pilot.tuning.lambda = tuneLambda(scene, *this, pilotSeed(seed), pilot.candidates);
    // dtheta is measured at the jump size the chains will use: how far a perturbation turns a medium vertex
    // depends on it (medium_angle_pilot.h).
    if (mediumAngleAuto())
        pilot.tuning.mediumAngle =
            pilotMediumAngle(scene, *this, pilotSeed(seed), pilot.candidates, pilot.tuning.lambda).angle;
    pilot.candidates.clear();  // the pilot ships luminance sums and what it tuned only
    return pilot;
}

double ERPT::expectedChains(double candidateWeight, double meanLuminance, double chainsPerPixel) const {
    const double nu = meanLuminance > 0 ? chainsPerPixel * candidateWeight / meanLuminance : chainsPerPixel;
    return maxChains_ > 0 ? std::min(nu, static_cast<double>(maxChains_)) : nu;
}

uint64_t ERPT::chainTaskCount(const Scene &scene, int64_t spp) const {
    return static_cast<uint64_t>(spp) * plan(scene, spp).tasksPerRound();
}

ChainTask ERPT::chainTask(const Scene &scene, const Normalizer &normalizer, uint64_t, int64_t spp,
                          uint64_t index) const {
    const BurstPlan p = plan(scene, spp);
    ChainTask task;
    task.index = index;
    task.mutations = static_cast<uint64_t>(chainLength_);
    task.depthLuminance = normalizer.depthLuminance();
    task.tuning = normalizer.tuning();
    task.burst =
        BurstPass{index / p.blocks, index % p.blocks, normalizer.luminance() / static_cast<double>(p.pixels), p};
    return task;
}

std::vector<ChainSeed> ERPT::taskSeeds(const Scene &scene, uint64_t seed, const ChainTask &task,
                                       uint64_t &seedSamples) const {
    if (!task.burst) throw std::logic_error("an erpt chain task without its pass");
    const BurstPass &b = *task.burst;
    const double coverage = static_cast<double>(b.plan.interleave);
    PCG32 rng(hashCombine(seed, task.index), kChainCountStream);
    std::vector<ChainSeed> seeds;
    for (const SeedCandidate &c : burstCandidates(scene, seeding(scene), seed, b, seedSamples)) {
        // A pass covers the pixel with probability 1/m, so the seed stands for m w (render/burst.h).
        const double nu = expectedChains(c.weight, b.meanLuminance, b.plan.chainsPerPixel);
        const int chains = static_cast<int>(std::floor(nu + rng.nextDouble()));
        for (int k = 0; k < chains; ++k) seeds.push_back({c.record, coverage * c.weight / nu});
    }
    return seeds;
}

double ERPT::chainImageScale(const Scene &scene, int64_t spp, const ChainImage &image, double) const {
    return image.tasks > 0 ? static_cast<double>(tasksPerPass(scene, spp)) / static_cast<double>(image.tasks) : 0.0;
}

}  // namespace pf
