// The master's durable state in SQLite: jobs, the tasks issued for them, every attempt (lease) of every
// task, accepted results, the merges contained in each job's film checkpoint, workers and per-job
// blocklists. Film data (results, checkpoints) lives in files the rows name; a row is written only after
// its file is complete, so a crash at any point leaves a state the master can resume from.
//
// Task work is stored as a serialized TaskSpec (its `work` oneof), so new task kinds need no schema
// change. All methods are thread-safe (one connection behind a mutex) and throw StorageError on
// database errors (a full disk among them).
#pragma once
#include <sqlite3.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "pathfarm/v1/common.pb.h"
#include "pathfarm/v1/worker.pb.h"
#include "storage_error.h"

namespace pf::master {

using pathfarm::v1::Job;
using pathfarm::v1::TaskSpec;
using pathfarm::v1::TaskStats;
using pathfarm::v1::WorkerInfo;

// States of a task row and of an attempt row, as stored (text, so that the store reads well in sqlite3).
namespace task_state {
inline constexpr const char *kPending = "pending", *kLeased = "leased", *kAccepted = "accepted", *kMerged = "merged";
}
namespace attempt_state {
// `ignored`: the attempt's result arrived after the task had been given to another attempt.
inline constexpr const char *kLeased = "leased", *kCompleted = "completed", *kFailed = "failed", *kExpired = "expired",
                            *kCancelled = "cancelled", *kIgnored = "ignored", *kReleased = "released";
}  // namespace attempt_state

struct StoredJob {
    Job record;              // spec, state, error, times, figures
    int64_t mergedTasks;     // tasks [0, mergedTasks) are in the checkpoint
    std::string checkpoint;  // file of the merged film ("" before the first checkpoint)
};

struct StoredTask {
    int64_t index;
    TaskSpec work;  // only the `work` oneof is meaningful
    std::string state;
};

struct StoredAttempt {
    int64_t id, taskIndex;
    std::string workerId, state;
};

struct StoredResult {
    int64_t taskIndex, attemptId;
    std::string file;
    TaskStats stats;
};

class Store {
public:
    // Opens or creates the store and checks its integrity (PRAGMA quick_check): a damaged file is
    // refused at start with the reason, never half-read into a running farm.
    explicit Store(const std::string &path);
    ~Store();
    Store(const Store &) = delete;
    Store &operator=(const Store &) = delete;

    // Inserts the job and returns its id (also written into the stored record).
    int64_t createJob(Job &job);
    void saveJob(const Job &job);

    // Leases tasks (several: a batch) in one transaction: inserts each task's row first if it is new
    // (isNew[i]), marks it leased and records the attempt. Returns the attempts' ids, in order.
    std::vector<int64_t> leaseTasks(int64_t job, const std::vector<TaskSpec> &tasks, const std::vector<bool> &isNew,
                                    const std::string &worker, int64_t nowMs);
    // Ends an attempt without a result (failed, expired, cancelled); its task becomes pending again
    // unless the job is over.
    void endAttempt(int64_t attempt, const std::string &state, const std::string &error, int64_t nowMs);
    // Ends every leased attempt of a job (cancellation).
    void cancelAttempts(int64_t job, int64_t nowMs);
    // Records that a late result of a superseded attempt was refused.
    void ignoreAttempt(int64_t attempt, int64_t nowMs);
    // The result of `attempts` (of `tasks`, one each: a batch holds several) is stored in `file`: attempts
    // completed, tasks accepted, results recorded, in one transaction. The batch's later tasks are recorded
    // with the same file, no bytes and empty stats, so that sums over results stay right.
    void acceptResult(int64_t job, const std::vector<int64_t> &tasks, const std::vector<int64_t> &attempts,
                      const std::string &file, uint64_t bytes, const TaskStats &stats, int64_t nowMs);
    // The film checkpoint `file` contains tasks [0, mergedTasks): tasks [fromTask, mergedTasks) are
    // recorded as merged, and the job's record saved, in one transaction.
    void commitCheckpoint(const Job &job, int64_t fromTask, int64_t mergedTasks, const std::string &file,
                          int64_t nowMs);
    // The stored result of `task` is lost (unreadable or failing its checksum): its row goes and the task
    // is pending again, to be rendered anew.
    void discardResult(int64_t job, int64_t task);
    // The job's checkpointed film is lost: every task merged into it is pending again (its result rows
    // go, and so do its rows in `merges`, which describe a film that no longer exists). Returns the
    // files of the removed result rows.
    std::vector<std::string> rewindJob(int64_t job);
    void blocklist(int64_t job, const std::string &worker, const std::string &reason);
    void saveWorker(const WorkerInfo &w);

    std::vector<StoredJob> loadJobs();
    std::vector<StoredTask> loadTasks(int64_t job);
    std::vector<StoredAttempt> loadAttempts(int64_t job);  // all attempts, in id order
    std::vector<StoredResult> loadUnmergedResults(int64_t job);
    // The results of tasks [0, toTask), merged or not, whose files still exist (results a Markov-chain job
    // keeps for its lifetime: its seeding).
    std::vector<StoredResult> loadResults(int64_t job, int64_t toTask);
    std::vector<std::string> loadBlocklist(int64_t job);
    std::vector<WorkerInfo> loadWorkers();

private:
    class Stmt;
    void exec(const char *sql);
    void setJobState(int64_t job, const Job &record);
    template <class Arg>
    std::vector<StoredResult> loadResults(const char *sql, int64_t job, Arg arg);

    sqlite3 *db_ = nullptr;
    std::mutex mu_;
};

}  // namespace pf::master
