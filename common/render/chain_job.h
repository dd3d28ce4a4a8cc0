// A Markov-chain render as one list of tasks in merge order (ARCHITECTURE.md "A job, end to end"):
// the seeding tasks, then the image tasks of the direct component (Mitsuba's directSamples, rendered
// without chains), then the chain tasks. The chain tasks can only be formed once every seeding task is
// merged (they carry starts resampled from the whole pool, ALGORITHMS.md §2.4). The embedded renderer
// (ChainIntegrator::render) and the farm's master both drive a ChainJob, so they form the same tasks and
// merge each component in the same order, which gives the same bits wherever the tasks ran.
#pragma once
#include <cstdint>
#include <optional>
#include <vector>

#include "render/chain.h"
#include "render/image_task.h"
#include "render/normalizer.h"

namespace pf {

// The seed of a job's direct component: a stream apart from the seeding's and the chains'.
uint64_t directComponentSeed(uint64_t jobSeed);

class ChainJob {
public:
    // `spp` mutations per pixel (0: a time budget, where the clock decides how many chain tasks run).
    ChainJob(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, int64_t spp);

    const Scene &scene() const { return scene_; }
    const ChainIntegrator &integrator() const { return integrator_; }
    uint64_t seed() const { return seed_; }

    // ---- the task list: [0, S) seeding, [S, S + D) direct component, [S + D, ...) chains ----
    enum class Phase { Seeding, Direct, Chain };
    uint64_t seedingTaskCount() const { return seedingTasks_.size(); }
    uint64_t directTaskCount() const { return directTasks_.size(); }
    uint64_t firstChainTask() const { return seedingTaskCount() + directTaskCount(); }
    Phase phaseOf(uint64_t task) const;
    const SeedingTask &seedingTask(uint64_t task) const { return seedingTasks_.at(task); }
    const SeedingConfig &seedingConfig() const { return config_; }
    // The direct component's task `task` (a job task index in [S, S + D)) and the seed it renders with.
    const ImageTask &directTask(uint64_t task) const { return directTasks_.at(task - seedingTaskCount()); }
    uint64_t directSeed() const { return directComponentSeed(seed_); }
    // Chain tasks exist once seeded(): how many (0 when the pool carries no energy, UINT64_MAX under a time
    // budget), and task `task` (a job task index >= S + D).
    bool seeded() const { return normalizer_.has_value(); }
    const Normalizer &normalizer() const { return *normalizer_; }
    uint64_t chainTaskCount() const;
    ChainTask chainTask(uint64_t task) const;

    // ---- merging, each component in task order ----
    // The last seeding result builds the normalizer.
    void mergeSeeding(SeedingResult result);
    void mergeDirect(const ImageBlock &block, int64_t samplesPerPixel);
    void mergeChain(const ChainResult &result) { mergeChainResult(chains_, result); }
    // Puts back the merged direct component and chains of a checkpoint (after the seeding is merged again).
    void restore(ImageBlock direct, int64_t directSamplesPerPixel, ChainImage chains);

    const ImageBlock &direct() const { return direct_; }
    int64_t directSamplesPerPixel() const { return directSpp_; }
    const ChainImage &chains() const { return chains_; }
    // Mutations per pixel merged so far.
    int64_t mutationsPerPixel() const;
    // The image so far: the developed chains (once seeded) plus the direct component.
    Bitmap develop() const;

private:
    const Scene &scene_;
    const ChainIntegrator &integrator_;
    uint64_t seed_;
    int64_t spp_;
    SeedingConfig config_;
    std::vector<SeedingTask> seedingTasks_;
    std::vector<ImageTask> directTasks_;
    std::vector<SeedingResult> seeding_;  // merged so far, until the normalizer takes them
    std::optional<Normalizer> normalizer_;
    ImageBlock direct_;
    int64_t directSpp_ = 0;
    ChainImage chains_;
};

}  // namespace pf
