// The Master's in-memory model of jobs, their tasks and films, and workers, shared by the files that
// implement the class (master.h lists them). Which mutex guards what: everything in JobRuntime and
// WorkerRuntime is under Master::mu_, except the JobFilm, which is under its own mutex (taken before mu_,
// never after). Internal to the master; nothing outside master/ includes it.
#pragma once
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "master.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace pf::master {

inline int64_t unixMs() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
}

inline bool isActive(pathfarm::v1::JobState s) {
    return s == pathfarm::v1::JOB_QUEUED || s == pathfarm::v1::JOB_RUNNING;
}

// The wall time a result took its worker to render: TaskStats.seconds, except for a batch of chain tasks, whose
// seconds are the sum over tasks that ran one per thread at once (on a worker of `threads` threads). The master
// takes it from the time between lease and acceptance to find the result's transfer (JobRuntime::overheadSeconds).
inline double renderWallSeconds(const pathfarm::v1::TaskSpec &work, int64_t tasks, int threads,
                                const pathfarm::v1::TaskStats &stats) {
    if (!work.has_chain() || tasks <= 1) return stats.seconds();
    return stats.seconds() / static_cast<double>(std::min<int64_t>(tasks, std::max(threads, 1)));
}

// Size of every image task of a job; a time budget draws tasks as an unbounded spp budget does (so a timed
// job that ended after n tasks has exactly the bits of an spp job of the same sample count, and one that ended
// with a partial task has them where that task left pixels alone, and the next count's where it covered them).
inline int64_t taskSize(const pathfarm::v1::Job &job, int64_t firstSample) {
    const auto &budget = job.spec().budget();
    return imageTaskSize(budget.has_spp() ? budget.spp() : std::numeric_limits<int64_t>::max(), firstSample,
                         int64_t{job.width()} * job.height());
}

struct Master::Loaded {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Integrator> integrator;
};

// A Markov-chain job's film side: the scene and integrator its chain tasks are formed with, and the
// ChainJob that forms them and merges the results.
struct Master::ChainState {
    Loaded loaded;
    std::unique_ptr<ChainJob> job;
};

struct Master::TaskRuntime {
    enum class State { Pending, Leased, Accepted, Merged };
    pathfarm::v1::TaskSpec work;  // task_index and work
    State state = State::Pending;
    int64_t attempt = 0;             // the latest attempt; only its result is accepted
    std::set<std::string> failedOn;  // workers on which an attempt failed
    int failures = 0;
    Clock::time_point leased{};  // of the latest attempt; the epoch for tasks leased before a restart
};

struct Master::JobFilm {
    std::mutex mu;
    std::shared_ptr<Film> film;  // set once before the job is visible; immutable after
    // What the merged results form, released when the job ends: an image job's film, or a Markov-chain
    // job's ChainState.
    std::optional<ImageBlock> block;
    std::unique_ptr<ChainState> chain;
    bool open() const { return block || chain; }
    int64_t merged = 0;  // tasks [0, merged) are in `block`
    // Tasks after `merged` that are in `block` too: the rest of a chain batch whose row passed a direct task not
    // yet merged. Checkpoints wait until it is empty, since a checkpoint holds tasks [0, merged) only.
    std::set<int64_t> mergedAhead;
    int64_t checkpointed = 0;   // tasks [0, checkpointed) are in the checkpoint file
    int64_t spp = 0;            // image jobs: samples per pixel merged, in whole tasks
    int64_t partialPixels = 0;  // image jobs: the pixels of a merged partial last task (render/image_task.h)
    struct Pending {
        std::string file;
        pathfarm::v1::TaskStats stats;
        pathfarm::v1::TaskSpec work;
        // The result as complete() decoded it, kept while the film's held bytes stay within kHeldBytes, so that
        // a result that arrives before its turn is not read back and decoded a second time when its turn comes
        // (with many workers most results arrive out of order). Without it the file is read.
        std::optional<TaskOutput> output;
        size_t bytes = 0;
        // The tasks of the result, its key first (Master::batchRow); a batched image result's `work` holds their
        // samples together.
        std::vector<int64_t> tasks;
        // Its time from the lease to its acceptance beyond the worker's rendering and scene load: the transfer
        // both ways, the worker's encoding, the master's decoding. Negative where the lease time is unknown.
        double transferSeconds = -1;
    };
    std::map<int64_t, Pending> pending;  // accepted, waiting for their turn
    // Decoded image results' blocks, reused once merged (decodeBlock overwrites every value): allocating
    // and clearing a film of doubles per result cost the master as much as decoding it (perf under
    // bench_farm). Under spareMu alone; decodeOutput takes them without the film mutex.
    static constexpr size_t kSpareBlocks = 2;
    mutable std::mutex spareMu;
    mutable std::vector<ImageBlock> spareBlocks;
    static constexpr size_t kHeldBytes = size_t{128} << 20;
    size_t heldBytes = 0;  // of the pending outputs held in memory
    // Their result files, deleted once checkpointed (a chain job's seeding results are kept: they are
    // merged again after a restart).
    std::vector<std::string> mergedSinceCheckpoint;
    std::string checkpointFile;
    Clock::time_point lastCheckpoint = Clock::now();
    // The last developed image, of tasks [0, previewMerged).
    std::shared_ptr<const Bitmap> preview;
    int64_t previewMerged = 0;
    Clock::time_point lastPreview;
    Clock::duration checkpointCost{};  // of the last checkpoint
    std::string storageFault;          // the last failed write of this film's files, logged once
};

struct Master::JobRuntime {
    pathfarm::v1::Job record;        // spec, state, error, times and merged figures; counts are filled in by snapshot()
    std::vector<TaskRuntime> tasks;  // issued tasks, by index
    std::set<int64_t> retry;         // issued tasks waiting for another attempt, lowest first
    int64_t nextFirstSample = 0;
    int64_t total = 0;  // tasks the job will have; 0 while a time budget is open or the seeding runs
    // An image job's time budget ends with a partial task of this many tiles (mayIssue chooses it, nextTaskFor
    // issues it and closes the budget); 0: none chosen.
    int64_t partialTiles = 0;
    // Markov-chain jobs: tasks [0, chainFirst) seed the chains and render the direct component; chain tasks
    // are issued once `seeded` (the normalizer exists, and is immutable from then on).
    bool chain = false;
    int64_t seedingTasks = 0, chainFirst = 0, seedingSpp = 0;
    bool seeded = false;
    std::map<std::string, int> failuresByWorker;
    std::set<std::string> blocklist;
    // Accepted results of the tasks a time budget issues, for its estimate of the next ones: chain tasks
    // are alike, image tasks grow (render/image_task.h), so theirs is per sample per pixel.
    double taskSeconds = 0;
    int64_t taskCount = 0;
    int64_t taskSpp = 0;  // image jobs
    // Image jobs: the tiles' rendering times of the last whole task that reported them (TaskStats.tile_seconds),
    // which size the partial task by what the film's first tiles cost.
    std::vector<float> tileSeconds;
    void countTime(const pathfarm::v1::TaskSpec &work, int64_t tasks, const pathfarm::v1::TaskStats &stats) {
        if (work.has_image() && work.image().tiles() > 0) return;  // a partial task: the last one anyway
        if (stats.tile_seconds_size() > 0) tileSeconds.assign(stats.tile_seconds().begin(), stats.tile_seconds().end());
        taskSeconds += stats.seconds();
        taskCount += tasks;
        if (work.has_image()) taskSpp += work.image().sample_count();
    }
    // What a task costs the job's clock beyond its rendering (Pending::transferSeconds and the merge), averaged
    // over the results merged so far: the budget must hold it too, since the job ends with its last merge.
    // (A 1024² BDPT job under --time 30 ran 31.0 s on one worker while only the rendering was counted.)
    double overheadSeconds = 0;
    int64_t overheadCount = 0;
    double expectedOverhead() const {
        return overheadCount > 0 ? overheadSeconds / static_cast<double>(overheadCount) : 0.0;
    }
    // The time one worker is expected to take for image tasks of `spp` samples per pixel in all, or for one
    // chain task; 0 before a result is in.
    double expectedSeconds(int64_t spp) const {
        if (chain) return taskCount > 0 ? taskSeconds / static_cast<double>(taskCount) : 0.0;
        return taskSpp > 0 ? taskSeconds * static_cast<double>(spp) / static_cast<double>(taskSpp) : 0.0;
    }
    int64_t passStartMs = 0;  // when the last pass's first task was issued (0: not since the start)
    int64_t failedAttempts = 0, expiredAttempts = 0;
    std::map<int64_t, int64_t> attemptTask;  // every attempt of this job -> its task
    // Every attempt -> the worker it was leased to: only that worker's result is taken, also after the
    // lease expired (a worker cannot deliver for a task it never leased).
    std::map<int64_t, std::string> attemptWorker;
    bool filmOpen = false;  // the film still holds memory or result files to release once the job ends
    JobFilm film;
};

struct Master::WorkerRuntime {
    pathfarm::v1::WorkerInfo info;
    Clock::time_point lastSeen;
    bool draining = false;
    std::set<int64_t> attempts;
    // Attempts whose results were accepted since the worker's last heartbeat. The worker lists an attempt in its
    // heartbeats until its upload's reply reaches it, so a heartbeat may cross the accepted result: those attempts
    // are done, not lost, and the next heartbeat forgets them.
    std::set<int64_t> delivered;
    // Completed tasks in their two units: pixel samples (image and seeding tasks), mutations (chains).
    double renderSeconds = 0, mutationSeconds = 0;
    uint64_t samples = 0, mutations = 0;
};

}  // namespace pf::master
