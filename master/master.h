// The master's state and scheduling, independent of gRPC: jobs and their tasks, leases with deadlines,
// retries and blocklists, exact in-order merging of results, checkpoints and recovery after a restart.
// Image jobs (path, volpath, bdpt) are lists of ImageTasks; Markov-chain jobs (pssmlt, mmlt, mlt, erpt,
// ...) are the task list of a render/chain_job.h ChainJob: seeding tasks, the direct component's image
// tasks, then chain tasks, which are formed once the seeding is merged (ARCHITECTURE.md "A job, end to
// end").
// The gRPC services (services.cpp) and the HTTP status module call this class; every public method is
// thread-safe. Its implementation is split by concern, one file each (the private section below lists
// what each holds):
//   master.cpp         construction, status queries and metrics
//   job_lifecycle.cpp  submission, loading scenes, recovery after a restart, job states, cancelling
//   scheduler.cpp      workers, leases, which task a worker gets next, failures, the reaper's expiry
//   merger.cpp         a result's way from complete() through decoding and the in-order merge to the
//                      checkpoint, the final image and previews
//   chain_jobs.cpp     what a Markov-chain job does differently from an image job
//   runtime.h          the in-memory model those files share (jobs, tasks, films, workers)
//
// Locking: `mu_` guards scheduling state and is only held for short, non-blocking work plus store
// writes. Each job's film has its own mutex, held while results are merged and checkpoints written;
// it may be taken before `mu_`, never after (so a film mutex is never awaited while `mu_` is held).
#pragma once
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "batch_governor.h"
#include "farm/bundle.h"
#include "image/bitmap.h"
#include "image/film.h"
#include "pathfarm/v1/client.pb.h"
#include "pathfarm/v1/worker.pb.h"
#include "render/chain_job.h"
#include "store.h"

namespace pf::master {

using Clock = std::chrono::steady_clock;
using pathfarm::v1::JobSpec;

struct MasterConfig {
    std::string dataDir = "pathfarm-data";
    std::chrono::milliseconds leaseTime{10000};           // a lease not renewed for this long is expired
    std::chrono::milliseconds heartbeat{3000};            // how often workers renew
    std::chrono::milliseconds checkpointInterval{10000};  // at least; see mergeReady
    int maxFailuresPerWorker = 3;  // failed or expired attempts of one job before a worker is blocklisted
    int maxFailuresPerTask = 5;    // failed attempts of one task before its job fails
    // Per-job limits.
    int64_t maxPixels = int64_t(16) << 20;
    int64_t maxSpp = int64_t(1) << 20;
    double maxTimeSeconds = 7 * 24 * 3600.0;
    uint64_t maxBundleBytes = uint64_t(2) << 30;
    int maxMessageBytes = 4 << 20;  // gRPC messages in either direction
    // Batches for workers that leave their size to the master (batch_governor.h): they grow while taking
    // results uses more than this share of one master core, measured over windows of batchWindow.
    double batchBusyShare = 0.5;
    std::chrono::milliseconds batchWindow{1000};
};

// Figures for status pages and /metrics.
struct MasterMetrics {
    std::map<std::string, int64_t> tasksByState;  // pending, leased, accepted, merged
    std::map<std::string, int64_t> jobsByState;
    int64_t workers = 0, workersAlive = 0;
    uint64_t samplesMerged = 0;    // pixel samples (v1::Job.samples) since the master started
    uint64_t mutationsMerged = 0;  // Markov-chain mutations since the master started
    double samplesPerSecond = 0;   // pixel samples, over the last minute
    int64_t resultsMerged = 0;     // since the master started
    double mergeSeconds = 0;       // decoding and merging those results
    uint64_t resultBytes = 0;      // their payloads on the wire
    int64_t lateResultsIgnored = 0;
    int64_t resultsLost = 0;  // stored results unreadable or failing their checksum, rendered again
    int64_t attemptsExpired = 0, attemptsFailed = 0, attemptsReleased = 0;
    int batchTasks = 1;  // the batch a worker with `--batch auto` gets now
};

// Thrown for requests naming a worker the master does not know (the worker registers again).
struct UnknownWorker : std::runtime_error {
    using std::runtime_error::runtime_error;
};

class Master {
public:
    // Opens (or creates) the data directory and resumes every unfinished job in it.
    explicit Master(MasterConfig config);
    ~Master();
    Master(const Master &) = delete;
    Master &operator=(const Master &) = delete;

    const MasterConfig &config() const { return cfg_; }
    farm::BundleStore &bundles() { return bundles_; }

    // ---- clients ----
    // Validates the spec against the limits, loads the scene from its bundle and builds the integrator
    // (so that bad scenes and parameters are reported to the submitter, naming file and line), then
    // queues the job. Throws farm::FarmError or SceneError with a message for the user.
    pathfarm::v1::Job submit(const JobSpec &spec);
    std::optional<pathfarm::v1::Job> job(int64_t id) const;
    std::vector<pathfarm::v1::Job> jobs() const;
    std::optional<pathfarm::v1::Job> cancel(int64_t id);
    // A counter that grows whenever any job changes; waitForChange blocks until it exceeds `seen` or
    // the timeout passes, and returns its value.
    uint64_t changeCount() const;
    uint64_t waitForChange(uint64_t seen, std::chrono::milliseconds timeout) const;
    // The job's image as EXR file content: the final image of a finished job, else the running image.
    struct ExrImage {
        std::string bytes;
        bool final = false;
        int64_t samplesPerPixel = 0;
        double partialPassShare = 0;  // of the pixels, with a partial last task's sample
    };
    std::optional<ExrImage> image(int64_t id) const;
    // The job's image as merged so far, or nullptr before the first merge. Developed here, on request,
    // at most four times a second and only when results merged since: a merge never develops the film
    // for a preview nobody looks at.
    std::shared_ptr<const Bitmap> preview(int64_t id);
    std::vector<pathfarm::v1::WorkerInfo> workers() const;
    MasterMetrics metrics() const;

    // ---- workers ----
    pathfarm::v1::RegisterReply registerWorker(const pathfarm::v1::RegisterRequest &req, const std::string &peer);
    // The most image tasks one lease (and one batched result) holds.
    static constexpr int kMaxBatchTasks = 64;
    // The most chain tasks one lease holds. A chain task's film covers most of the image whatever its length
    // (erpt at 1024²: 20 MB of tiles for 0.4 core-seconds), so a batch's result costs the master about as much
    // as one task's, and only long batches let one master feed many workers: 64 tasks kept 11.5 eight-core
    // workers per master core busy on erpt at 1024² (bench_farm part 6).
    static constexpr int kMaxChainBatchTasks = 1024;
    // A task for this worker, waiting up to `wait` for one; empty when there is none (or the worker
    // drains). With maxTasks > 1, the tasks of its kind that follow it in its job too (image tasks of an image
    // job, chain tasks of a chain job; up to maxTasks, capped at kMaxBatchTasks or kMaxChainBatchTasks, as many
    // as can be leased now, and no more than the worker's share of a fixed budget's tasks not yet issued), for a
    // batched result; with farm::kAutoBatch, up to the governor's batch. Throws UnknownWorker.
    std::vector<pathfarm::v1::TaskSpec> lease(const std::string &worker, std::chrono::milliseconds wait,
                                              int maxTasks = 1);
    // Renews the worker's leases; returns the attempts it no longer holds. Throws UnknownWorker.
    std::vector<int64_t> heartbeat(const std::string &worker, const std::vector<int64_t> &attempts, bool draining);
    // Whether a result for `attempt` would be accepted now; "" if so, else the reason it is not.
    std::string checkAttempt(const std::string &worker, int64_t attempt) const;
    // Upper bound of a result payload for `attempt` (decoded size plus zstd's worst case).
    uint64_t maxPayloadBytes(int64_t attempt) const;
    // Takes a result: validates and stores it, then merges every result that is next in task order. A
    // batched result names several attempts: the tasks of one of the job's batch rows (batchRow), in order
    // (else farm::FarmError); it is taken whole or not at all, and merged once as one result.
    pathfarm::v1::CompleteReply complete(const std::string &worker, const std::vector<int64_t> &attempts,
                                         const pathfarm::v1::TaskStats &stats, const std::string &payload);
    // Refuses a result that checkAttempt() found stale, recording late results of superseded attempts.
    pathfarm::v1::CompleteReply ignoreResult(const std::string &worker, int64_t attempt, const std::string &reason);
    // The attempt ended without a result: it failed (counted against the task and the worker), or, `released`, its
    // draining worker gave it back unstarted.
    void fail(const std::string &worker, int64_t attempt, const std::string &error, bool released = false);

private:
    // The in-memory model of jobs, their tasks and films, and workers (runtime.h).
    struct Loaded;
    struct ChainState;
    struct TaskRuntime;
    struct JobFilm;
    struct JobRuntime;
    struct WorkerRuntime;
    struct Lease {
        int64_t job, task;
        std::string worker;
        Clock::time_point deadline;
    };

    // ---- master.cpp ----
    std::string jobDir(int64_t id) const;
    void touch();  // under mu_: counts a change and wakes waitForChange

    // ---- job_lifecycle.cpp ----
    void recover();
    void recoverJob(const StoredJob &stored);
    // Loads the job's scene and integrator from its bundle and fills in the record's scene figures.
    Loaded load(const JobSpec &spec, pathfarm::v1::Job &record) const;
    // Sets up the job's film side (the merged film, or the ChainJob) from what load() returned.
    void openFilm(JobRuntime &j, Loaded loaded);
    // After a restart: the opened film as the stored checkpoint has it. Throws farm::FarmError when the
    // checkpoint or a file it depends on is unreadable or damaged.
    void restoreFilm(JobRuntime &j, const StoredJob &stored);
    // Under mu_.
    pathfarm::v1::Job snapshot(const JobRuntime &j) const;
    void setState(JobRuntime &j, pathfarm::v1::JobState state, const std::string &error = "");

    // ---- scheduler.cpp ----
    void reaperLoop();
    // Under mu_: expires the leases and marks lost the workers whose time ran out by `now`.
    void expire(Clock::time_point now);
    // Under mu_.
    std::optional<pathfarm::v1::TaskSpec> pickTask(WorkerRuntime &w);
    // Leases the job's tasks `indices` to the worker (a new attempt each, stored in one transaction).
    // Throws StorageError (the tasks are then queued again).
    std::vector<pathfarm::v1::TaskSpec> leaseIndices(JobRuntime &j, WorkerRuntime &w,
                                                     const std::vector<int64_t> &indices);
    std::optional<int64_t> nextTaskFor(JobRuntime &j, const WorkerRuntime &w);
    bool mayIssue(JobRuntime &j);
    // Ends a time budget: no task after those issued.
    void closeTimeBudget(JobRuntime &j);
    // Whether task `index` of j may be part of a batch: an image job's whole tasks (not the partial last one),
    // a chain job's chain tasks (not its seeding or direct tasks).
    static bool batchable(const JobRuntime &j, int64_t index);
    // The tasks of a batch of `count` tasks from `first`, in order: an image job's follow each other; a chain
    // job's are its chain tasks from `first` on, past the direct tasks between them (lease leaves those to the
    // next request, so that they do not cut a worker's row of chain tasks). Shorter where the issued tasks end.
    static std::vector<int64_t> batchRow(const JobRuntime &j, int64_t first, size_t count);
    // Whether a batch's row passes over task `index` of j (a chain job's direct task) rather than holding it.
    static bool passedInRow(const JobRuntime &j, int64_t index);
    // Whether worker w may take j's tasks: it runs j's integrator (its `algorithms`, if it lists any) and is not
    // blocklisted for j.
    static bool mayRun(const JobRuntime &j, const WorkerRuntime &w);
    // The most tasks a batch of j's may hold for a worker that asked for maxTasks (farm::kAutoBatch: the
    // governor's choice), before time budgets have their say (batchMayGrow).
    size_t batchLimit(const JobRuntime &j, int maxTasks);
    // Whether a batch of the batchTasks tasks of j from firstTask, leased to a worker of `threads` threads, may
    // take one more (time budgets: if it still ends in time).
    bool batchMayGrow(const JobRuntime &j, int64_t firstTask, size_t batchTasks, int threads) const;
    // Ends the attempt in `state` and puts its task back in the queue; a failure is counted against the worker
    // unless the attempt was released.
    void requeue(JobRuntime &j, int64_t task, const std::string &worker, const std::string &state,
                 const std::string &error, int64_t attempt);
    void countFailure(JobRuntime &j, const std::string &worker, const std::string &why);

    // ---- merger.cpp ----
    // A result payload decoded by its task's kind: the film block of an image task, a seeding result, a
    // chain result. Throws farm::FarmError when it is corrupt.
    using TaskOutput = std::variant<ImageBlock, SeedingResult, ChainResult>;
    TaskOutput decodeOutput(const JobRuntime &j, const pathfarm::v1::TaskSpec &work, std::string_view payload) const;
    // Film side: called with the job's film mutex held.
    void mergeReady(JobRuntime &j, std::optional<std::pair<int64_t, TaskOutput>> fresh);
    // The memory a decoded result holds while it waits for its turn (0: not worth holding).
    static size_t heldBytes(const TaskOutput &output);
    // Merges the result of `tasks` tasks (a batch: more than one) that starts with `work`'s.
    void mergeOutput(JobRuntime &j, const pathfarm::v1::TaskSpec &work, TaskOutput output, int64_t tasks);
    // The pending result of `tasks` is lost: they go back to the queue (takes mu_).
    void discardResult(JobRuntime &j, const std::vector<int64_t> &tasks, const std::string &file);
    // Logs a failed write of the job's film files once per distinct fault.
    void storageFault(JobRuntime &j, const char *what, const std::exception &e);
    // Throws StorageError.
    void checkpoint(JobRuntime &j);
    void finishIfComplete(JobRuntime &j);
    void writeFinalImage(JobRuntime &j, double seconds);
    void closeFilm(JobRuntime &j);
    Bitmap develop(const JobRuntime &j) const;

    // ---- chain_jobs.cpp: Markov-chain jobs ----
    // Task `index` of a chain job (chain tasks only once it is seeded), as the store and the workers see it.
    static pathfarm::v1::TaskSpec chainTaskWork(const ChainJob &job, uint64_t index);
    // Whether task `index` of a chain job is the first of a pass (a time budget issues whole passes).
    static bool startsPass(const JobRuntime &j, int64_t index);
    // openFilm for a chain job: the ChainJob that forms its tasks, and its figures in the record.
    void openChainFilm(JobRuntime &j, Loaded loaded, const ChainIntegrator &integrator);
    // After a restart: merges the stored seeding results again and restores the checkpoint's direct
    // component and chains. Throws when they cannot be read.
    void restoreChainFilm(JobRuntime &j, const StoredJob &stored);
    // Upper bound of a seeding result's payload.
    static uint64_t maxSeedingPayloadBytes(const JobRuntime &j, const pathfarm::v1::TaskSpec &work);
    // mergeOutput for a chain job's tasks (film mutex held).
    static void mergeChainOutput(JobFilm &f, const pathfarm::v1::TaskSpec &work, TaskOutput output, int64_t tasks);
    // Under both mutexes, after a merge: the record's chain figures, and the chain phase once seeded.
    void recordChainMerge(JobRuntime &j, uint64_t seedingSamples, uint64_t directSamples);
    // Once the seeding is merged: the chain phase starts (called with both mutexes held).
    void startChains(JobRuntime &j);
    // The checkpoint file's content for a chain job (film mutex held).
    static std::string chainCheckpoint(const ChainJob &job);

    MasterConfig cfg_;
    farm::BundleStore bundles_;
    Store store_;
    mutable std::mutex sceneLoadMu_;  // one scene load at a time bounds the master's memory
    // Decompression buffers of decodeOutput, reused for the reason of JobFilm::spareBlocks.
    mutable std::mutex scratchMu_;
    mutable std::vector<std::vector<unsigned char>> scratch_;
    static constexpr size_t kSpareScratch = 4;

    mutable std::mutex mu_;
    mutable std::condition_variable workChanged_;  // a task may have become available
    mutable std::condition_variable jobChanged_;
    uint64_t changes_ = 0;
    std::map<int64_t, std::unique_ptr<JobRuntime>> jobs_;
    std::map<int64_t, Lease> leases_;  // by attempt id
    std::map<std::string, std::unique_ptr<WorkerRuntime>> workers_;
    MasterMetrics counters_;
    mutable BatchGovernor batchGovernor_;
    // Samples merged per second (seconds since the steady clock's epoch), over the last minute.
    std::deque<std::pair<int64_t, uint64_t>> recentSamples_;

    bool stopping_ = false;
    std::thread reaper_;
};

}  // namespace pf::master
