// Between seeding and chains, and after the chains: the estimate b̂ of the total image luminance, the
// resampling of chain starts from the seeding pool, and the merge and normalization rules of the chain
// films (ALGORITHMS.md §2.3-2.5, §5.3), in one place.
//
// Resampling (§2.4): every chain's start is drawn from the pool with probability w_i / W. The chains of one
// task are drawn together by systematic resampling (one uniform number per task, strata over the pool's
// cumulative weights, which run in pixel order, so a task's chains also spread over the image); tasks draw
// independently (generators seeded by (job seed, task index)), so the starts do not depend on how many
// tasks a time budget lets run. Each of the K long chains then carries weight W / K, which the long-chain rule
// applies at merge time: image = b̂ * (sum of films) / (sum of mutations), with b̂ = W from the same pool,
// which makes the image exactly unbiased for any fixed chain lengths. Bursts (§5.3) have no pool: their
// tasks sample their own seeds (render/burst.h), and the image is the mean of whole passes' films.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "render/chain.h"
#include "render/seeding.h"

namespace pf {

class Normalizer {
public:
    // The results of every seeding task of a job, in task order (pixel order).
    explicit Normalizer(std::vector<SeedingResult> results);

    // b̂ = W, the sum of all candidate weights.
    double luminance() const { return luminance_; }
    const std::vector<double> &depthLuminance() const { return depthLuminance_; }
    const std::vector<SeedCandidate> &candidates() const { return pool_; }
    // What a seeding result tuned (lambda or manifoldMediumAngle = "auto"); zeros where none did.
    const ManifoldTuning &tuning() const { return tuning_; }
    // Two-stage MLT: the first stage's image I that the chains' target is divided by (render/two_stage.h);
    // the candidates' weights, b̂ and the luminance per depth are then those of that target.
    const FirstStageImage &firstStage() const { return firstStage_; }

    // The starts of the `count` long chains of task `taskIndex` (weight 1: the merge rule applies W / K);
    // none when the pool carries no energy.
    std::vector<ChainSeed> resample(uint64_t seed, uint64_t taskIndex, uint64_t count) const;

private:
    // Index into pool_ of the candidate at cumulative weight `target`.
    size_t find(double target) const;
    void reweightForSecondStage();

    std::vector<SeedCandidate> pool_;
    std::vector<double> cumulative_;  // cumulative_[i] = sum of the weights before candidate i (size + 1)
    std::vector<double> depthLuminance_;
    double luminance_ = 0;
    ManifoldTuning tuning_;
    FirstStageImage firstStage_;
};

// The merged chain films of a render (or of a farm job so far).
struct ChainImage {
    explicit ChainImage(ImageBlock empty) : film(std::move(empty)) {}
    ImageBlock film;
    uint64_t mutations = 0;
    uint64_t tasks = 0;        // chain task results merged
    uint64_t seedSamples = 0;  // BDPT samples burst tasks took for their seeds
    MutationCounts counts;
    ChainCounters counters;
    uint64_t rays = 0;
    double seconds = 0;  // summed over tasks (core seconds)
};

// The factor a chain's deposits carry: 1 for long chains, weight / M for bursts.
double chainDepositScale(ChainKind kind, const ChainSeed &seed, uint64_t mutations);
// Adds a task's result, or the sum of `tasks` tasks' results (a farm worker's batch, addChainResult). Tasks
// merged in the same order give the same bits; a batch's sum rounds differently in the last bits.
void mergeChainResult(ChainImage &image, const ChainResult &result, uint64_t tasks = 1);
// Adds `result` to `sum`, both films as tiles (render/chain.h): what a farm worker returns for a batch of chain
// tasks, so that the master decodes and merges one film for all of them.
void addChainResult(ChainResult &sum, const ChainResult &result);
// The normalized image: the films times `scale` (ChainIntegrator::chainImageScale).
Bitmap developChains(const Film &film, const ChainImage &image, double scale);

}  // namespace pf
