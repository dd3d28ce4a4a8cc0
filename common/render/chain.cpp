// Chain tasks, and the embedded renderer of Markov-chain integrators: the tasks of a ChainJob (seeding,
// then passes of chain tasks with the direct component's tasks between them), merged in task order so that the
// image does not depend on the thread count (ARCHITECTURE.md "A job, end to end").
#include "render/chain.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "integrators/progress_bar.h"
#include "render/chain_job.h"
#include "scene/scene.h"

namespace pf {

namespace {

using Clock = std::chrono::steady_clock;

constexpr uint64_t kChainStream = 0xc4a1ULL;
// A chain task's mutations: one per crop pixel within these bounds. The upper bound is what a timed render
// cannot undercut (its first wave runs one task per core whatever the budget): 2^16 BDPT-evaluated
// mutations take 2-5 s on one core for pssmlt on cornell-box or veach-bidir (2^18 took 17-35 s at 1024²).
constexpr uint64_t kMinTaskMutations = 1u << 14, kMaxTaskMutations = 1u << 16;

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

// Runs run(i) for i in [0, n) on `threads` threads and hands each result to merge() in index order, as soon
// as it and those before it are done. A task starts only while fewer than two per thread wait for their
// turn, so at most 3 * threads results (films) are held, whatever n and however uneven the tasks.
template <class Run, class Merge>
void runOrdered(size_t n, int threads, const Run &run, const Merge &merge) {
    using Result = decltype(run(size_t(0)));
    std::mutex mu;
    std::condition_variable cv;
    std::map<size_t, Result> done;
    size_t next = 0, merged = 0;
    const size_t window = 2 * static_cast<size_t>(threads);
    parallelFor(n, threads, [&](size_t) {
        size_t i;
        {
            std::unique_lock<std::mutex> lock(mu);
            cv.wait(lock, [&] { return next < merged + window; });
            i = next++;
        }
        Result r = run(i);
        std::unique_lock<std::mutex> lock(mu);
        done.emplace(i, std::move(r));
        // Whoever completes the next result in order merges it (and those after it that wait), under the lock.
        for (auto it = done.find(merged); it != done.end(); it = done.find(merged)) {
            merge(it->second);
            done.erase(it);
            ++merged;
        }
        cv.notify_all();
    });
}

}  // namespace

ChainResult runChainTask(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, const ChainTask &task) {
    const auto start = Clock::now();
    const uint64_t rays0 = Scene::threadRayCount();
    // Tiles: a chain's deposits cover little of the window (a burst task's stay near its band of pixels).
    ChainResult result{makeFilmBlock(scene, BlockStorage::Tiles), 0, 0, integrator.mutationTypes(), {}, 0, 0};
    const std::vector<ChainSeed> seeds = integrator.taskSeeds(scene, seed, task, result.seedSamples);
    PCG32 rng(hashCombine(seed, task.index), kChainStream);
    for (const ChainSeed &s : seeds)
        integrator.runChain(scene, seed, task, s, chainDepositScale(integrator.chainKind(), s, task.mutations), rng,
                            result.film, result.counts, result.counters);
    result.mutations = task.mutations * seeds.size();
    result.rays = Scene::threadRayCount() - rays0;
    result.seconds = secondsSince(start);
    return result;
}

uint64_t chainTaskMutations(const Scene &scene) {
    return std::clamp(cropPixels(scene), kMinTaskMutations, kMaxTaskMutations);
}

SeedingResult ChainIntegrator::runSeeding(const Scene &scene, int64_t spp, uint64_t seed,
                                          const SeedingTask &task) const {
    return runSeedingTask(scene, seeding(scene, spp), seed, task);
}

std::vector<SeedingTask> ChainIntegrator::seedingTasks(const Scene &scene) const { return pf::seedingTasks(scene); }

std::vector<ChainSeed> ChainIntegrator::taskSeeds(const Scene &, uint64_t, const ChainTask &task, uint64_t &) const {
    return task.seeds;
}

double ChainIntegrator::chainImageScale(const Scene &, int64_t, const ChainImage &image, double luminance) const {
    return image.mutations > 0 ? luminance / static_cast<double>(image.mutations) : 0.0;
}

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
    task.firstStage = normalizer.firstStage();
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
    const bool timed = opt.timeLimit > 0 && opt.passes <= 0;
    const int64_t spp = timed || opt.passes > 0 ? 0 : (opt.spp > 0 ? opt.spp : scene.sensor().sampleCount());
    ChainJob job(scene, *this, opt.seed, spp);

    // The job's tasks in its merge order (render/chain_job.h): seeding first.
    ProgressBar progress(opt.progress);
    progress.update(0, "seeding");
    std::vector<SeedingResult> seeds(job.seedingTaskCount());
    parallelFor(seeds.size(), threads,
                [&](size_t i) { seeds[i] = runSeeding(scene, spp, opt.seed, job.seedingTask(i)); });
    for (SeedingResult &r : seeds) {
        stats.rays += r.rays;
        job.mergeSeeding(std::move(r));
    }

    // Then whole passes, each with the direct tasks before it (render/chain_job.h), in units of at least one
    // chain task per core. Under a time budget the clock decides whether another unit starts, from the
    // expected duration of that unit; a burst render is unbiased only over whole passes (render/burst.h).
    const uint64_t count = job.taskCount();
    const auto passEnd = [&](uint64_t t) {
        for (++t; t < count && !job.startsPass(t);) ++t;
        return t;
    };
    // The clock's estimate of a unit: the direct and the chain tasks' mean wall times so far, each times
    // their count in the unit (units differ: only some carry direct tasks, which at 1024² take seconds).
    double directSeconds = 0, chainSeconds = 0;
    uint64_t directDone = 0, chainDone = 0;
    const uint64_t passLimit = opt.passes > 0 ? static_cast<uint64_t>(opt.passes) : UINT64_MAX;
    for (uint64_t next = job.firstChainTask(), passes = 0; next < count && passes < passLimit;) {
        uint64_t end = next, chainTasks = 0;
        while (end < count && chainTasks < static_cast<uint64_t>(threads) && passes < passLimit) {
            const uint64_t e = passEnd(end);
            for (uint64_t t = end; t < e; ++t) chainTasks += job.phaseOf(t) == ChainJob::Phase::Chain;
            end = e;
            ++passes;
        }
        const uint64_t directTasks = end - next - chainTasks;
        const double estimate =
            (directDone > 0 ? directSeconds / static_cast<double>(directDone) * static_cast<double>(directTasks) : 0) +
            (chainDone > 0 ? chainSeconds / static_cast<double>(chainDone) * static_cast<double>(chainTasks) : 0);
        if (timed && next > job.firstChainTask() && secondsSince(start) + estimate > opt.timeLimit) break;
        std::vector<uint64_t> chainIndices;
        const auto directStart = Clock::now();
        for (uint64_t t = next; t < end; ++t) {
            if (job.phaseOf(t) == ChainJob::Phase::Chain) {
                chainIndices.push_back(t);
                continue;
            }
            const ImageTask direct = job.directTask(t);
            const ImageTaskResult r = runDirectTask(scene, *this, opt.seed, direct, threads);
            stats.rays += r.rays;
            job.mergeDirect(r.block, direct.sampleCount);
        }
        directSeconds += secondsSince(directStart);
        directDone += directTasks;
        const auto chainStart = Clock::now();
        runOrdered(
            chainIndices.size(), threads,
            [&](size_t i) { return runChainTask(scene, *this, opt.seed, job.chainTask(chainIndices[i])); },
            [&](const ChainResult &r) { job.mergeChain(r); });
        chainSeconds += secondsSince(chainStart);
        chainDone += chainTasks;
        next = end;
        char label[96];
        std::snprintf(label, sizeof label, "%llu passes, %lld mutations/px, %lld direct spp, %.1f s",
                      static_cast<unsigned long long>(job.passesMerged()),
                      static_cast<long long>(job.mutationsPerPixel()),
                      static_cast<long long>(job.directSamplesPerPixel()), secondsSince(start));
        progress.update(timed                     ? secondsSince(start) / opt.timeLimit
                        : passLimit != UINT64_MAX ? static_cast<double>(passes) / static_cast<double>(passLimit)
                                                  : static_cast<double>(next - job.firstChainTask()) /
                                                        static_cast<double>(count - job.firstChainTask()),
                        label);
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
