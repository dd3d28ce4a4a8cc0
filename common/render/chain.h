// The chain phase of Markov-chain rendering (ALGORITHMS.md §2.4-2.5; ARCHITECTURE.md "A job, end to end",
// steps 3-4): a ChainTask runs one or more Markov chains from resampled seeding candidates for a fixed
// number of mutations each and returns an unnormalized film with per-mutation-type statistics. The
// algorithm and its parameters are the job's integrator (a ChainIntegrator); everything else a chain
// needs is in the task, and its random numbers come from a generator seeded by (job seed, task index), so
// a task is a pure function of (scene, integrator, job seed, task): a retried task returns the same bits.
//
// Two kinds of chains (§2.5): long chains (PSSMLT, MMLT, MLT) deposit f / pi per unit of expected-value
// weight and are normalized by b̂ / (total mutations) when merged; bursts (ERPT, §5.3) carry their seed's
// weight W / C and deposit weight / M * f / pi, and are merged by summing. render/normalizer.h holds both
// rules.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "image/film.h"
#include "integrators/integrator.h"
#include "mcmc/metropolis.h"
#include "render/burst.h"
#include "render/seeding.h"

namespace pf {

enum class ChainKind { Long, Burst };

// A chain's start: a seeding candidate, and for bursts the chain's weight (W_p / C; 1 for long chains).
struct ChainSeed {
    PathRecord record;
    double weight = 1;
};

struct ChainTask {
    uint64_t index = 0;            // the task's random stream within the job
    std::vector<ChainSeed> seeds;  // one chain per seed, run one after the other
    uint64_t mutations = 0;        // per chain, fixed in advance (§2.5: never cut by the clock)
    // The seeding's luminance per path depth; the sum is b̂. Chains with Kelemen's weights need it.
    std::vector<double> depthLuminance;
    // Bursts: the pass and block whose seeds the task samples itself (render/burst.h); `seeds` is empty.
    std::optional<BurstPass> burst;
    // The manifold perturbation's jump size and medium dtheta as the pilot tuned them; 0: the integrator's.
    ManifoldTuning tuning;
    // Two-stage MLT: the first stage's image; the chains' target is L / I (render/two_stage.h).
    FirstStageImage firstStage;
};

struct ChainResult {
    ImageBlock film;  // unnormalized deposits (splats) over the crop window, in tiles (BlockStorage::Tiles)
    uint64_t mutations = 0;
    uint64_t seedSamples = 0;  // BDPT samples a burst task took for its seeds
    MutationCounts counts;
    ChainCounters counters;  // further statistics (mcmc/metropolis.h), e.g. the manifold walks
    uint64_t rays = 0;
    double seconds = 0;
};

class Normalizer;
struct ChainImage;

// Markov-chain integrators: seeding, then chains. render() is the embedded renderer (render/chain.cpp);
// the farm calls the same pieces (seedingTasks/runSeedingTask, Normalizer, chainTask/runChainTask).
class ChainIntegrator : public Integrator {
public:
    virtual ChainKind chainKind() const { return ChainKind::Long; }
    // The seeding the chains start from, for a job of `spp` (the budget of render(); 0: a time budget or
    // the scene's sampleCount). Only ERPT-type bursts take their seeds per pixel from it.
    virtual SeedingConfig seeding(const Scene &scene, int64_t spp = 0) const = 0;
    // The mutation types of this algorithm's chains, with zero counts, in MutationCount index order.
    virtual MutationCounts mutationTypes() const = 0;
    // Runs one chain of task.mutations steps from `seed`, drawing from `rng`, and deposits into `film` with
    // its deposits multiplied by `scale`, counting its transitions in `counts` and anything else it
    // measures in `counters`.
    virtual void runChain(const Scene &scene, uint64_t jobSeed, const ChainTask &task, const ChainSeed &seed,
                          double scale, PCG32 &rng, ImageBlock &film, MutationCounts &counts,
                          ChainCounters &counters) const = 0;
    // The budget (as `spp`) whose passes a time budget runs, as far as the clock allows, and whose pace the direct
    // component keeps under it (render/chain_job.h): the scene's sampleCount.
    virtual int64_t timeBudgetPlan(const Scene &scene) const;
    // The component rendered without chains (Mitsuba's directSamples), its samples per pixel; null if none.
    virtual const SamplingIntegrator *directIntegrator() const { return nullptr; }
    virtual int64_t directSamples() const { return 0; }

    // The chain tasks of a render with `spp` mutations per pixel: how many, and task `index` (spp = 0: a
    // time budget, where the clock decides how many tasks run and each has taskMutations()). Long
    // chains: the budget is split into tasks of at most taskMutations() mutations whose sizes differ by
    // at most one, each running chainsPerTask() chains of equal length (the task's size rounded down to a
    // multiple of the chain count), their starts resampled per task (Normalizer::resample).
    virtual uint64_t chainTaskCount(const Scene &scene, int64_t spp) const;
    virtual ChainTask chainTask(const Scene &scene, const Normalizer &normalizer, uint64_t seed, int64_t spp,
                                uint64_t index) const;
    virtual uint64_t chainsPerTask(const Scene &) const { return 1; }
    // Mutations per long-chain task (what chainTaskCount splits a budget by): chainTaskMutations by default.
    virtual uint64_t taskMutations(const Scene &scene) const;
    // Runs seeding task `task` of a job of `spp`: by default runSeedingTask with seeding(scene, spp).
    virtual SeedingResult runSeeding(const Scene &scene, int64_t spp, uint64_t seed, const SeedingTask &task) const;
    // The seeding tasks of a job: by default blocks of pixels (render/seeding.h) whose candidates form the
    // pool of chain starts; burst integrators run the luminance pilot alone (render/pilot.h).
    virtual std::vector<SeedingTask> seedingTasks(const Scene &scene) const;
    // The starts of a task's chains: its resampled seeds; burst tasks sample their own (render/burst.h),
    // counting the BDPT samples that took in `seedSamples`.
    virtual std::vector<ChainSeed> taskSeeds(const Scene &scene, uint64_t seed, const ChainTask &task,
                                             uint64_t &seedSamples) const;
    // Chain tasks per pass of a render of `spp` (as chainTaskCount): a time budget stops a render only
    // between passes. Long chains: every task.
    virtual uint64_t tasksPerPass(const Scene &, int64_t) const { return 1; }
    // The factor that turns the merged chain films of a render of `spp` into the image
    // (render/normalizer.h): long chains b̂ / (merged mutations), with b̂ = `luminance` from the seeding.
    virtual double chainImageScale(const Scene &scene, int64_t spp, const ChainImage &image, double luminance) const;

    Bitmap render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const override;
};

ChainResult runChainTask(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, const ChainTask &task);

// Mutations per long-chain task: one per pixel, so that a task's film is worth shipping, but never fewer than
// 2^14 and never more than `most` (2^16 by default). A time budget stops only between tasks, and 2^20 mutations
// (1024²) are 10-30 core-seconds of PSSMLT: `pssmlt --time 30` at 1024² rendered 61 s with such tasks.
uint64_t chainTaskMutations(const Scene &scene, uint64_t most = uint64_t{1} << 16);

}  // namespace pf
