// Chain tasks, and the embedded renderer of Markov-chain integrators: the tasks of a ChainJob (seeding,
// the direct component, then waves of chain tasks, one task per core), merged in task order so that the
// image does not depend on the thread count (ARCHITECTURE.md "A job, end to end").
#include "render/chain.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <optional>
#include <thread>

#include "render/chain_job.h"
#include "scene/scene.h"

namespace pf {

namespace {

using Clock = std::chrono::steady_clock;

constexpr uint64_t kChainStream = 0xc4a1ULL;
constexpr uint64_t kMinTaskMutations = 1u << 14;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

uint64_t cropPixels(const Scene &scene) {
    const Film &film = scene.sensor().film();
    return static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
}

// Runs fn(i) for i in [0, n) on `threads` threads.
template <class Fn>
void parallelFor(size_t n, int threads, const Fn &fn) {
    std::atomic<size_t> next{0};
    auto worker = [&]() {
        for (size_t i; (i = next.fetch_add(1)) < n;) fn(i);
    };
    std::vector<std::thread> pool;
    for (int k = 1; k < std::min<int>(threads, static_cast<int>(n)); ++k) pool.emplace_back(worker);
    worker();
    for (auto &t : pool) t.join();
}

}  // namespace

ChainResult runChainTask(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, const ChainTask &task) {
    const auto start = Clock::now();
    const uint64_t rays0 = Scene::threadRayCount();
    ChainResult result{makeFilmBlock(scene), 0, integrator.mutationTypes(), {}, 0, 0};
    PCG32 rng(hashCombine(seed, task.index), kChainStream);
    for (const ChainSeed &s : task.seeds)
        integrator.runChain(scene, seed, task, s, chainDepositScale(integrator.chainKind(), s, task.mutations), rng,
                            result.film, result.counts, result.counters);
    result.mutations = task.mutations * task.seeds.size();
    result.rays = Scene::threadRayCount() - rays0;
    result.seconds = secondsSince(start);
    return result;
}

uint64_t chainTaskMutations(const Scene &scene) { return std::max(kMinTaskMutations, cropPixels(scene)); }

uint64_t ChainIntegrator::chainTaskCount(const Scene &scene, int64_t spp) const {
    const uint64_t total = static_cast<uint64_t>(spp) * cropPixels(scene), length = chainTaskMutations(scene);
    return (total + length - 1) / length;
}

ChainTask ChainIntegrator::chainTask(const Scene &scene, const Normalizer &normalizer, uint64_t seed, int64_t spp,
                                     uint64_t index) const {
    const uint64_t chains = chainsPerTask(scene);
    ChainTask task;
    task.index = index;
    task.seeds = normalizer.resample(seed, index, chains);
    task.depthLuminance = normalizer.depthLuminance();
    uint64_t size = chainTaskMutations(scene);
    if (spp > 0) {
        const uint64_t total = static_cast<uint64_t>(spp) * cropPixels(scene), count = chainTaskCount(scene, spp);
        size = total / count + (index < total % count ? 1 : 0);
    }
    task.mutations = size / chains;
    return task;
}

Bitmap ChainIntegrator::render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const {
    const auto start = Clock::now();
    const int threads =
        opt.threads > 0 ? opt.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    // Under a time budget the clock decides whether another wave of whole chains starts, never when a chain
    // stops (ALGORITHMS.md §2.5).
    const bool timed = opt.timeLimit > 0;
    const int64_t spp = timed ? 0 : (opt.spp > 0 ? opt.spp : scene.sensor().sampleCount());
    ChainJob job(scene, *this, opt.seed, spp);

    // The job's tasks in its merge order (render/chain_job.h): seeding, direct component, chains.
    std::vector<SeedingResult> seeds(job.seedingTaskCount());
    parallelFor(seeds.size(), threads,
                [&](size_t i) { seeds[i] = runSeedingTask(scene, job.seedingConfig(), opt.seed, job.seedingTask(i)); });
    for (SeedingResult &r : seeds) {
        stats.rays += r.rays;
        job.mergeSeeding(std::move(r));
    }
    for (uint64_t t = job.seedingTaskCount(); t < job.firstChainTask(); ++t) {
        const ImageTaskResult r =
            runImageTask(scene, *directIntegrator(), job.directSeed(), job.directTask(t), threads);
        stats.rays += r.rays;
        job.mergeDirect(r.block, job.directTask(t).sampleCount);
    }

    const uint64_t count = job.chainTaskCount();
    double lastWave = 0;
    for (uint64_t next = 0; next < count;) {
        if (timed && next > 0 && secondsSince(start) + lastWave > opt.timeLimit) break;
        const auto waveStart = Clock::now();
        const size_t n = static_cast<size_t>(std::min<uint64_t>(static_cast<uint64_t>(threads), count - next));
        std::vector<std::optional<ChainResult>> results(n);
        parallelFor(n, threads, [&](size_t i) {
            results[i] = runChainTask(scene, *this, opt.seed, job.chainTask(job.firstChainTask() + next + i));
        });
        for (const auto &r : results) job.mergeChain(*r);
        next += n;
        lastWave = secondsSince(waveStart);
        if (opt.onPass) opt.onPass(job.mutationsPerPixel(), job.develop());
    }
    const ChainImage &image = job.chains();
    stats.rays += image.rays;
    stats.samples = image.mutations;
    stats.counts = image.counts;
    stats.counters = image.counters;
    stats.samplesPerPixel = job.mutationsPerPixel();
    stats.seconds = secondsSince(start);
    return job.develop();
}

}  // namespace pf
