#include "integrators/erpt.h"

#include <algorithm>
#include <cmath>

#include "render/normalizer.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The stream of the rounding of chain counts, apart from every other generator of the job.
constexpr uint64_t kChainCountStream = 0xe127ULL;

// The crop window split into a fixed number of pixel blocks (16, or fewer for tiny films, more for large
// ones so that no block exceeds 16384 pixels), independent of the thread count.
uint64_t cropPixels(const Scene &scene) {
    const Film &film = scene.sensor().film();
    return static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
}
uint64_t blockCount(const Scene &scene) {
    const uint64_t pixels = cropPixels(scene);
    return std::min(pixels, std::max<uint64_t>(16, (pixels + 16383) / 16384));
}

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
    // Mitsuba estimates the mean pixel luminance W with a separate pass of this many samples; here W comes
    // from the seeding itself, and the parameter is only checked, so that Mitsuba's scenes load.
    if (props.getInt("luminanceSamples", 15000) < 1) props.fail("luminanceSamples", "must be at least 1");
    if (!(numChains_ > 0)) props.fail("numChains", "must be positive");
    if (maxChains_ < 0) props.fail("maxChains", "must be 0 (no cap) or positive");
    if (chainLength_ < 1) props.fail("chainLength", "must be at least 1");
}

SeedingConfig ERPT::seeding(const Scene &scene, int64_t spp) const {
    return seedingWith(spp > 0 ? spp : scene.sensor().sampleCount());
}

double ERPT::expectedChains(double candidateWeight, double meanLuminance) const {
    const double nu = numChains_ * candidateWeight / meanLuminance;
    return maxChains_ > 0 ? std::min(nu, static_cast<double>(maxChains_)) : nu;
}

uint64_t ERPT::chainTaskCount(const Scene &scene, int64_t) const { return blockCount(scene); }

ChainTask ERPT::chainTask(const Scene &scene, const Normalizer &normalizer, uint64_t seed, int64_t,
                          uint64_t index) const {
    const Film &film = scene.sensor().film();
    const uint64_t pixels = cropPixels(scene), blocks = blockCount(scene);
    const double mean = normalizer.luminance() / static_cast<double>(pixels);
    ChainTask task;
    task.index = index;
    task.mutations = static_cast<uint64_t>(chainLength_);
    task.depthLuminance = normalizer.depthLuminance();
    // A time budget asks for tasks beyond the last block: the bursts of every pixel are all there is (the
    // films are summed, so a second pass would count twice), and those tasks are empty.
    if (index >= blocks) return task;
    // The candidates that the block's pixels generated (the pool is in pixel order).
    const std::vector<SeedCandidate> &pool = normalizer.candidates();
    const uint64_t first = filmPixel(film, index * pixels / blocks),
                   last = filmPixel(film, (index + 1) * pixels / blocks - 1);
    const auto begin =
        std::partition_point(pool.begin(), pool.end(), [&](const SeedCandidate &c) { return c.record.pixel < first; });
    const auto end =
        std::partition_point(begin, pool.end(), [&](const SeedCandidate &c) { return c.record.pixel <= last; });
    PCG32 rng(hashCombine(seed, index), kChainCountStream);
    for (auto c = begin; c != end; ++c) {
        const double nu = expectedChains(c->weight, mean);
        const int chains = static_cast<int>(std::floor(nu + rng.nextDouble()));
        for (int k = 0; k < chains; ++k) task.seeds.push_back({c->record, c->weight / nu});
    }
    return task;
}

}  // namespace pf
