#include "render/burst.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "scene/scene.h"

namespace pf {

namespace {

// The stream of each round's interleave offset o_r, apart from every other generator of the job.
constexpr uint64_t kInterleaveStream = 0x1e7ea5eULL;

uint64_t ceilDiv(double a, double b) { return static_cast<uint64_t>(std::max(1.0, std::ceil(a / b))); }

}  // namespace

BurstPlan burstPlan(const Scene &scene, double chainsPerPixel, int64_t chainLength, int64_t passMutations) {
    const Film &film = scene.sensor().film();
    BurstPlan plan;
    plan.pixels = static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
    plan.chainsPerPixel = chainsPerPixel;
    const double roundMutations = static_cast<double>(plan.pixels) * chainsPerPixel * static_cast<double>(chainLength);
    const double pass = static_cast<double>(passMutations);
    plan.interleave = std::min(plan.pixels, ceilDiv(roundMutations, pass));
    const uint64_t passPixels = plan.pixels / plan.interleave;
    plan.blocks = std::min(passPixels, ceilDiv(roundMutations / static_cast<double>(plan.interleave),
                                               pass / static_cast<double>(kBlocksPerPass)));
    return plan;
}

std::vector<SeedCandidate> burstCandidates(const Scene &scene, const SeedingConfig &config, uint64_t seed,
                                           const BurstPass &task, uint64_t &samples) {
    const Film &film = scene.sensor().film();
    const BurstPlan &plan = task.plan;
    // The pixels come from the scene: a plan from the wire carries only m and the blocks.
    const uint64_t pixels = static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
    if (plan.interleave < 1 || plan.interleave > pixels || plan.blocks < 1 || task.block >= plan.blocks)
        throw std::invalid_argument("a burst task's plan does not fit the film");
    const uint64_t m = plan.interleave, round = task.pass / m, phase = task.pass % m;
    PCG32 rng(hashCombine(seed, round), kInterleaveStream);
    const uint64_t offset = m > 1 ? rng.nextUInt(static_cast<uint32_t>(m)) : 0;
    const uint64_t first = task.block * pixels / plan.blocks, last = (task.block + 1) * pixels / plan.blocks;
    SeedingResult seeds;
    samples = 0;
    // The first covered pixel at or after `first`: (i + offset) mod m = phase.
    for (uint64_t i = first + (phase + m - (first + offset) % m) % m; i < last; i += m, ++samples)
        seedSample(scene, config, seed, filmPixel(film, i), round, 1.0, true, seeds);
    return std::move(seeds.candidates);
}

}  // namespace pf
