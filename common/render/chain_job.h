// A Markov-chain render as one list of tasks in merge order (ARCHITECTURE.md "A job, end to end"): the
// seeding tasks, then passes of chain tasks, each pass preceded by the image tasks of the direct component
// (Mitsuba's directSamples, rendered without chains, one or more samples per pixel each) that its share of
// the budget asks for. The chain tasks can only be formed once every seeding task is merged (they carry starts
// resampled from the whole pool, ALGORITHMS.md §2.4, or the pilot's W for bursts). The embedded renderer
// (ChainIntegrator::render) and the farm's master both drive a ChainJob, so they form the same tasks and
// merge each component in the same order, which gives the same bits wherever the tasks ran.
//
// Why the direct component is interleaved: at 1024² its 16 samples per pixel take minutes, so rendered
// up front it would swallow a time budget before the first chain ran. Spread over the passes, the direct
// samples issued after pass k are ceil((k + 1) · D / P) of D, P the passes of the render (under a time
// budget, of a render of the budget it plans, ChainIntegrator::timeBudgetPlan; past those, the direct
// component keeps that pace), at least one. A pass is the unit a time budget stops at
// (ChainIntegrator::tasksPerPass); any whole number of direct samples and of passes gives an unbiased image.
//
// Direct tasks of several samples. A direct task's result is a dense film of the crop window whatever its
// samples (22 MB on the wire at 1024²), and it cuts the row of chain tasks a farm worker may batch: at one sample
// per task, an erpt job at 1024² sent its master a direct task after every 48 chain tasks, a third of its
// results (bench_farm part 6). So its tasks grow: 1, 1, 2, 4, ... samples per pixel up to chunks of c, c = one per
// kDirectChunkPixels pixels of the crop window (8 at 1024², 1 up to 362², at most the direct samples). A task is
// issued as soon as the pace owes one of its samples, so the direct component runs ahead of the pace by less than
// a task, which is never more than the samples issued before it: a short render keeps about the pace's share,
// a long one sends whole chunks. (Held back instead until half a chunk of 8 was owed, the direct component of an
// erpt --time 30 farm job at 1024² stayed at one sample and the image's relMSE came to 0.0114, against 0.0051 with
// growing tasks; chunks of 8 from the second task on cost an embedded render of that budget a fifth of its
// mutations.)
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "render/chain.h"
#include "render/image_task.h"
#include "render/normalizer.h"

namespace pf {

// Crop-window pixels per sample of a direct task's chunk (ChainJob::directChunk).
constexpr uint64_t kDirectChunkPixels = uint64_t(1) << 17;

// Runs image task `task` of the direct component of a job with seed `jobSeed`: the integrator's direct
// component (integrators/path.h, makeDirectComponent) with a seed of its own, a stream apart from the seeding's
// and the chains', and low-discrepancy numbers in every request whatever the scene's sampler, as Mitsuba 0.6
// renders it (with an `ldsampler` of its own, libbidir's renderDirectComponent). On cornell-box at 64² and 16
// spp, independent numbers left 12 times the error of these in 8² block means (issue 17).
ImageTaskResult runDirectTask(const Scene &scene, const ChainIntegrator &integrator, uint64_t jobSeed,
                              const ImageTask &task, int threads);

class ChainJob {
public:
    // `spp` mutations per pixel (seed samples per pixel for bursts; 0: a time budget, where the clock
    // decides how many passes run).
    ChainJob(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, int64_t spp);

    const Scene &scene() const { return scene_; }
    const ChainIntegrator &integrator() const { return integrator_; }
    uint64_t seed() const { return seed_; }

    // ---- the task list: [0, S) seeding, then direct and chain tasks interleaved by pass ----
    enum class Phase { Seeding, Direct, Chain };
    uint64_t seedingTaskCount() const { return seedingTasks_.size(); }
    uint64_t firstChainTask() const { return seedingTaskCount(); }
    // The direct component's samples per pixel in a render of the budget (under a time budget: in one of
    // the budget it plans); 0 when there is none.
    int64_t directSamples() const { return directSamples_; }
    // The most samples per pixel a direct task holds (the chunk the tasks grow to), and the direct tasks of a
    // render of the budget.
    int64_t directChunk() const { return directChunk_; }
    uint64_t directTaskCount() const { return directTasks(static_cast<uint64_t>(directSamples_)); }
    const SeedingTask &seedingTask(uint64_t task) const { return seedingTasks_.at(task); }
    const SeedingConfig &seedingConfig() const { return config_; }
    // Tasks after the seeding exist once seeded(): how many in all (UINT64_MAX under a time budget), the
    // phase of task `task` (>= firstChainTask()), the direct component's task (its samples) and
    // the chain task, and whether `task` is the first of a pass's tasks (its direct tasks included).
    bool seeded() const { return normalizer_.has_value(); }
    const Normalizer &normalizer() const { return *normalizer_; }
    uint64_t taskCount() const;
    Phase phaseOf(uint64_t task) const;
    ImageTask directTask(uint64_t task) const;
    ChainTask chainTask(uint64_t task) const;
    bool startsPass(uint64_t task) const;

    // ---- merging, each component in task order ----
    // The last seeding result builds the normalizer.
    void mergeSeeding(SeedingResult result);
    void mergeDirect(const ImageBlock &block, int64_t samplesPerPixel);
    // A farm worker's batch comes as the sum of `tasks` chain tasks that follow each other (the direct tasks
    // between them apart, which merge into the other component).
    void mergeChain(const ChainResult &result, uint64_t tasks = 1) { mergeChainResult(chains_, result, tasks); }
    // Puts back the merged direct component and chains of a checkpoint (after the seeding is merged again).
    void restore(ImageBlock direct, int64_t directSamplesPerPixel, ChainImage chains);

    const ImageBlock &direct() const { return direct_; }
    int64_t directSamplesPerPixel() const { return directSpp_; }
    const ChainImage &chains() const { return chains_; }
    // Mutations per pixel merged so far.
    int64_t mutationsPerPixel() const;
    // Chain tasks per pass (1 for long chains), and the whole passes merged so far.
    uint64_t tasksPerPass() const { return integrator_.tasksPerPass(scene_, spp_); }
    uint64_t passesMerged() const { return chains_.tasks / tasksPerPass(); }
    // The image so far: the developed chains (once seeded) plus the direct component.
    Bitmap develop() const;

private:
    // Where task `task` (>= firstChainTask()) lies: its phase and its ordinal among the direct or the chain
    // tasks, with the pass it belongs to.
    struct Slot {
        Phase phase;
        uint64_t ordinal, pass;
    };
    Slot locate(uint64_t task) const;
    // The direct tasks issued before the chain tasks of pass k (all of them once k reaches the passes).
    uint64_t directBefore(uint64_t pass) const;
    // Direct task `task`'s samples per pixel (1, 1, 2, 4, ... up to directChunk_) and the samples of the tasks
    // before it; the direct tasks that hold `samples` samples per pixel, the last one possibly in part.
    uint64_t directSize(uint64_t task) const;
    uint64_t directStart(uint64_t task) const;
    uint64_t directTasks(uint64_t samples) const;
    uint64_t passCount() const;  // UINT64_MAX under a time budget

    const Scene &scene_;
    const ChainIntegrator &integrator_;
    uint64_t seed_;
    int64_t spp_;
    SeedingConfig config_;
    std::vector<SeedingTask> seedingTasks_;
    int64_t directSamples_ = 0, directChunk_ = 1;
    uint64_t pacePasses_ = 1;             // P: the passes over which the direct samples are spread
    std::vector<SeedingResult> seeding_;  // merged so far, until the normalizer takes them
    std::optional<Normalizer> normalizer_;
    ImageBlock direct_;
    int64_t directSpp_ = 0;
    ChainImage chains_;
};

}  // namespace pf
