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
// A chain task's mutations: one per crop pixel, at least this many. The upper bound (chainTaskMutations'
// `most`) is what a timed render cannot undercut (its first wave runs one task per core whatever the budget):
// 2^16 BDPT-evaluated mutations take 2-5 s on one core for pssmlt on cornell-box or veach-bidir (2^18 took
// 17-35 s at 1024²).
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

// Runs tasks on `threads` threads for as long as claim(wait) hands out their indices, and hands each result to
// merge() in the order of the claims, as soon as it and those before it are done. claim() and merge() run under
// one lock. claim() returns nothing either to stop (no more tasks are to start; the threads finish those they
// hold) or, having set `wait`, to be asked again once another result is merged. A task starts only while fewer than two
// per thread wait for their turn, so at most 3 * threads results (films) are held, however uneven the tasks. No thread
// waits for another between tasks: the embedded render's chain phase had every thread wait at the end of each wave of
// chain tasks (7% of two cores at 64², issue 17).
template <class Claim, class Run, class Merge>
void runOrdered(int threads, const Claim &claim, const Run &run, const Merge &merge) {
    using Result = decltype(run(uint64_t{0}));
    std::mutex mu;
    std::condition_variable cv;
    std::map<uint64_t, std::pair<uint64_t, Result>> done;  // by claim number: (index, result)
    uint64_t claimed = 0, merged = 0;
    bool exhausted = false;
    const uint64_t window = 2 * static_cast<uint64_t>(threads);
    const auto worker = [&] {
        for (;;) {
            uint64_t number, index;
            {
                std::unique_lock<std::mutex> lock(mu);
                cv.wait(lock, [&] { return exhausted || claimed < merged + window; });
                if (exhausted) return;
                bool wait = false;
                const std::optional<uint64_t> c = claim(wait);
                if (!c && wait) {
                    // Another thread holds a task (claim() waits only for one), so a merge will come.
                    const uint64_t m = merged;
                    cv.wait(lock, [&] { return exhausted || merged != m; });
                    continue;
                }
                if (!c) {
                    exhausted = true;
                    cv.notify_all();
                    return;
                }
                number = claimed++, index = *c;
            }
            Result r = run(index);
            const std::lock_guard<std::mutex> lock(mu);
            done.emplace(number, std::make_pair(index, std::move(r)));
            // Whoever completes the next result in order merges it (and those after it that wait).
            for (auto it = done.find(merged); it != done.end(); it = done.find(merged)) {
                merge(it->second.first, it->second.second);
                done.erase(it);
                ++merged;
            }
            cv.notify_all();
        }
    };
    std::vector<std::thread> pool;
    for (int k = 1; k < threads; ++k) pool.emplace_back(worker);
    worker();
    for (auto &t : pool) t.join();
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

uint64_t chainTaskMutations(const Scene &scene, uint64_t most) {
    return std::clamp(cropPixels(scene), kMinTaskMutations, std::max(most, kMinTaskMutations));
}

uint64_t ChainIntegrator::taskMutations(const Scene &scene) const { return chainTaskMutations(scene); }

int64_t ChainIntegrator::timeBudgetPlan(const Scene &scene) const { return std::max(1, scene.sensor().sampleCount()); }

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
    const uint64_t total = static_cast<uint64_t>(spp) * cropPixels(scene), length = taskMutations(scene);
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
    uint64_t size = taskMutations(scene);
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

    // Then whole passes, each with the direct tasks before it (render/chain_job.h), as one stream of tasks over
    // the threads, merged in task order. Under a time budget the clock decides whether another pass starts, from
    // its expected duration; the tasks of a started pass all run (a burst render is unbiased only over whole
    // passes, render/burst.h).
    const uint64_t count = job.taskCount(), first = job.firstChainTask();
    const auto isChain = [&](uint64_t t) { return job.phaseOf(t) == ChainJob::Phase::Chain; };
    const auto passEnd = [&](uint64_t t) {
        for (++t; t < count && !job.startsPass(t);) ++t;
        return t;
    };
    const uint64_t passLimit = opt.passes > 0 ? static_cast<uint64_t>(opt.passes) : UINT64_MAX;
    // The clock's estimate of a pass: the chain tasks' mean time and the direct component's time per sample so
    // far (each task runs on one thread; passes differ: only some carry direct tasks, which at 1024² take a
    // second or more per sample, and direct tasks differ in samples, render/chain_job.h), spread over the threads
    // but no shorter than its longest task. Until a chain task has finished there is no estimate: once one chain
    // task per thread has started (the first wave), the next pass waits for the first result.
    double directSeconds = 0, chainSeconds = 0;
    uint64_t directSamplesDone = 0, chainDone = 0, chainsClaimed = 0;
    const auto mean = [](double seconds, uint64_t n) { return n > 0 ? seconds / static_cast<double>(n) : 0.0; };
    uint64_t next = first, passes = 0, passStop = first;  // passStop: the end of the pass being claimed
    // chains: the pass's chain tasks; directSamples, longestDirect: its direct tasks' samples, all and the most.
    const auto startsInTime = [&](uint64_t chains, int64_t directSamples, int64_t longestDirect) {
        const double d = mean(directSeconds, directSamplesDone), c = mean(chainSeconds, chainDone);
        const double work = static_cast<double>(directSamples) * d + static_cast<double>(chains) * c;
        const double estimate =
            std::max({work / threads, chains > 0 ? c : 0.0, static_cast<double>(longestDirect) * d});
        return secondsSince(start) + estimate <= opt.timeLimit;
    };
    const auto claim = [&](bool &wait) -> std::optional<uint64_t> {
        if (next >= count) return std::nullopt;
        if (next == passStop) {
            if (passes >= passLimit) return std::nullopt;
            const uint64_t e = passEnd(next);
            uint64_t chains = 0;
            int64_t directSamples = 0, longestDirect = 0;
            for (uint64_t t = next; t < e; ++t) {
                if (isChain(t)) {
                    ++chains;
                } else {
                    const int64_t n = job.directTask(t).sampleCount;
                    directSamples += n;
                    longestDirect = std::max(longestDirect, n);
                }
            }
            if (timed && next > first && chains > 0 && chainDone == 0 &&
                chainsClaimed >= static_cast<uint64_t>(threads)) {
                wait = true;  // the first wave is out: wait for its first time
                return std::nullopt;
            }
            if (timed && next > first && !startsInTime(chains, directSamples, longestDirect)) return std::nullopt;
            passStop = e;
            ++passes;
        }
        chainsClaimed += isChain(next);
        return next++;
    };
    struct TaskResult {
        std::optional<ImageTaskResult> direct;
        std::optional<ChainResult> chain;
    };
    const auto run = [&](uint64_t t) {
        TaskResult r;
        if (isChain(t))
            r.chain = runChainTask(scene, *this, opt.seed, job.chainTask(t));
        else
            r.direct = runDirectTask(scene, *this, opt.seed, job.directTask(t), 1);
        return r;
    };
    const auto merge = [&](uint64_t t, const TaskResult &r) {
        if (r.chain) {
            job.mergeChain(*r.chain);
            chainSeconds += r.chain->seconds;
            ++chainDone;
        } else {
            stats.rays += r.direct->rays;
            const int64_t samples = job.directTask(t).sampleCount;
            job.mergeDirect(r.direct->block, samples);
            directSeconds += r.direct->seconds;
            directSamplesDone += static_cast<uint64_t>(samples);
        }
        if (t + 1 < count && !job.startsPass(t + 1)) return;
        char label[96];
        std::snprintf(label, sizeof label, "%llu passes, %lld mutations/px, %lld direct spp, %.1f s",
                      static_cast<unsigned long long>(job.passesMerged()),
                      static_cast<long long>(job.mutationsPerPixel()),
                      static_cast<long long>(job.directSamplesPerPixel()), secondsSince(start));
        progress.update(timed ? secondsSince(start) / opt.timeLimit
                        : passLimit != UINT64_MAX
                            ? static_cast<double>(job.passesMerged()) / static_cast<double>(passLimit)
                            : static_cast<double>(t + 1 - first) / static_cast<double>(count - first),
                        label);
        if (opt.onPass) opt.onPass(job.mutationsPerPixel(), job.develop());
    };
    runOrdered(threads, claim, run, merge);
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
