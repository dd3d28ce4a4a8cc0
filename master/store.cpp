#include "store.h"

#include <stdexcept>
#include <string_view>

namespace pf::master {

namespace {

// Written for humans reading the store with sqlite3 as much as for the master.
constexpr const char *kSchema = R"sql(
CREATE TABLE IF NOT EXISTS jobs (
  id INTEGER PRIMARY KEY,
  state INTEGER NOT NULL,              -- pathfarm.v1.JobState
  record BLOB NOT NULL,                -- serialized pathfarm.v1.Job (spec, state, times, figures)
  merged_tasks INTEGER NOT NULL DEFAULT 0,
  checkpoint TEXT NOT NULL DEFAULT ''  -- film file holding tasks [0, merged_tasks)
);
CREATE TABLE IF NOT EXISTS tasks (
  job_id INTEGER NOT NULL REFERENCES jobs(id),
  idx INTEGER NOT NULL,                -- merge order
  kind TEXT NOT NULL,                  -- the TaskSpec work kind
  work BLOB NOT NULL,                  -- serialized pathfarm.v1.TaskSpec with only `work` set
  state TEXT NOT NULL,                 -- pending, leased, accepted, merged
  PRIMARY KEY (job_id, idx)
);
CREATE TABLE IF NOT EXISTS attempts (
  id INTEGER PRIMARY KEY,
  job_id INTEGER NOT NULL,
  task_idx INTEGER NOT NULL,
  worker_id TEXT NOT NULL,
  state TEXT NOT NULL,                 -- leased, completed, failed, expired, cancelled, ignored, released
  leased_ms INTEGER NOT NULL,
  finished_ms INTEGER,
  error TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS attempts_job ON attempts(job_id, state);
CREATE TABLE IF NOT EXISTS results (
  job_id INTEGER NOT NULL,
  task_idx INTEGER NOT NULL,
  attempt_id INTEGER NOT NULL,
  file TEXT NOT NULL,
  bytes INTEGER NOT NULL,
  stats BLOB NOT NULL,                 -- serialized pathfarm.v1.TaskStats
  accepted_ms INTEGER NOT NULL,
  PRIMARY KEY (job_id, task_idx)
);
-- One row per task merged into a checkpointed film. Deliberately not unique: a task merged twice
-- would show up here as a second row.
CREATE TABLE IF NOT EXISTS merges (
  id INTEGER PRIMARY KEY,
  job_id INTEGER NOT NULL,
  task_idx INTEGER NOT NULL,
  checkpoint TEXT NOT NULL,
  merged_ms INTEGER NOT NULL
);
CREATE INDEX IF NOT EXISTS merges_task ON merges(job_id, task_idx);
CREATE TABLE IF NOT EXISTS workers (
  id TEXT PRIMARY KEY,
  info BLOB NOT NULL                   -- serialized pathfarm.v1.WorkerInfo
);
CREATE TABLE IF NOT EXISTS blocklist (
  job_id INTEGER NOT NULL,
  worker_id TEXT NOT NULL,
  reason TEXT NOT NULL,
  PRIMARY KEY (job_id, worker_id)
);
)sql";

// Serialized records are bound as BLOBs; every other string as TEXT (SQLite never finds a BLOB equal to
// a TEXT, so the two must not mix in one column).
struct Blob {
    std::string bytes;
};

Blob serialize(const google::protobuf::MessageLite &m) {
    Blob b;
    if (!m.SerializeToString(&b.bytes)) throw std::runtime_error("store: cannot serialize a record");
    return b;
}

}  // namespace

// A prepared statement with positional binding; finalized on destruction.
class Store::Stmt {
public:
    Stmt(sqlite3 *db, const char *sql) : db_(db) {
        if (sqlite3_prepare_v2(db, sql, -1, &s_, nullptr) != SQLITE_OK) fail("prepare");
    }
    ~Stmt() { sqlite3_finalize(s_); }
    Stmt(const Stmt &) = delete;
    Stmt &operator=(const Stmt &) = delete;

    template <typename... Args>
    Stmt &bind(const Args &...args) {
        int i = 1;
        (bindOne(i++, args), ...);
        return *this;
    }
    // Steps once; true while there is a row.
    bool step() {
        const int rc = sqlite3_step(s_);
        if (rc == SQLITE_ROW) return true;
        if (rc != SQLITE_DONE) fail("step");
        return false;
    }
    void run() {
        while (step()) {
        }
        sqlite3_reset(s_);  // ready to be bound and run again
    }
    int64_t integer(int col) const { return sqlite3_column_int64(s_, col); }
    std::string text(int col) const {
        const auto *p = static_cast<const char *>(sqlite3_column_blob(s_, col));
        return p ? std::string(p, static_cast<size_t>(sqlite3_column_bytes(s_, col))) : std::string();
    }

private:
    void bindOne(int i, int64_t v) { check(sqlite3_bind_int64(s_, i, v)); }
    void bindOne(int i, int v) { check(sqlite3_bind_int64(s_, i, v)); }
    void bindOne(int i, uint64_t v) { check(sqlite3_bind_int64(s_, i, static_cast<int64_t>(v))); }
    void bindOne(int i, const std::string &v) {
        check(sqlite3_bind_text(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
    }
    void bindOne(int i, const Blob &v) {
        check(sqlite3_bind_blob(s_, i, v.bytes.data(), static_cast<int>(v.bytes.size()), SQLITE_TRANSIENT));
    }
    void bindOne(int i, const char *v) { check(sqlite3_bind_text(s_, i, v, -1, SQLITE_TRANSIENT)); }
    void check(int rc) {
        if (rc != SQLITE_OK) fail("bind");
    }
    [[noreturn]] void fail(const char *what) const {
        throw StorageError(std::string("store: ") + what + ": " + sqlite3_errmsg(db_));
    }
    sqlite3 *db_;
    sqlite3_stmt *s_ = nullptr;
};

namespace {

// BEGIN IMMEDIATE ... COMMIT, rolled back if the scope is left by an exception.
class Transaction {
public:
    explicit Transaction(sqlite3 *db) : db_(db) { run("BEGIN IMMEDIATE"); }
    ~Transaction() {
        if (!done_) sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    }
    void commit() {
        run("COMMIT");
        done_ = true;
    }

private:
    void run(const char *sql) {
        char *err = nullptr;
        if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
            const std::string msg = err ? err : "unknown error";
            sqlite3_free(err);
            throw StorageError(std::string("store: ") + sql + ": " + msg);
        }
    }
    sqlite3 *db_;
    bool done_ = false;
};

}  // namespace

Store::Store(const std::string &path) {
    if (sqlite3_open(path.c_str(), &db_) != SQLITE_OK) {
        const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
        sqlite3_close(db_);
        throw StorageError("store: cannot open " + path + ": " + msg);
    }
    try {
        sqlite3_busy_timeout(db_, 5000);
        // WAL with synchronous=NORMAL survives a killed process (what the farm must survive); film files
        // are fsynced before the rows that name them are committed.
        exec("PRAGMA journal_mode=WAL");
        exec("PRAGMA synchronous=NORMAL");
        std::string problems;
        for (Stmt q(db_, "PRAGMA quick_check"); q.step();)
            if (const std::string row = q.text(0); row != "ok") problems += (problems.empty() ? "" : "; ") + row;
        if (!problems.empty()) throw StorageError("store: integrity check failed: " + problems.substr(0, 1000));
        exec(kSchema);
    } catch (const StorageError &e) {
        sqlite3_close(db_);
        throw StorageError(std::string(e.what()) + " (" + path +
                           " is damaged: restore it and its -wal file from a backup, or move them away to start "
                           "with an empty store)");
    }
}

Store::~Store() { sqlite3_close(db_); }

void Store::exec(const char *sql) {
    char *err = nullptr;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
        const std::string msg = err ? err : "unknown error";
        sqlite3_free(err);
        throw StorageError("store: " + msg);
    }
}

void Store::setJobState(int64_t job, const Job &record) {
    Stmt(db_, "UPDATE jobs SET state = ?, record = ? WHERE id = ?")
        .bind(static_cast<int>(record.state()), serialize(record), job)
        .run();
}

int64_t Store::createJob(Job &job) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    Stmt(db_, "INSERT INTO jobs (state, record) VALUES (?, x'')").bind(static_cast<int>(job.state())).run();
    job.set_id(sqlite3_last_insert_rowid(db_));
    setJobState(job.id(), job);
    tx.commit();
    return job.id();
}

void Store::saveJob(const Job &job) {
    const std::lock_guard<std::mutex> lock(mu_);
    setJobState(job.id(), job);
}

std::vector<int64_t> Store::leaseTasks(int64_t job, const std::vector<TaskSpec> &tasks, const std::vector<bool> &isNew,
                                       const std::string &worker, int64_t nowMs) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    std::vector<int64_t> attempts;
    for (size_t i = 0; i < tasks.size(); ++i) {
        const TaskSpec &task = tasks[i];
        if (isNew[i]) {
            TaskSpec work;
            const char *kind = task.has_image()     ? "image"
                               : task.has_seeding() ? "seeding"
                               : task.has_chain()   ? "chain"
                                                    : "";
            if (task.has_image()) *work.mutable_image() = task.image();
            if (task.has_seeding()) *work.mutable_seeding() = task.seeding();
            if (task.has_chain()) *work.mutable_chain() = task.chain();
            if (!*kind) throw std::runtime_error("store: a task without work");
            Stmt(db_, "INSERT INTO tasks (job_id, idx, kind, work, state) VALUES (?, ?, ?, ?, ?)")
                .bind(job, task.task_index(), kind, serialize(work), task_state::kLeased)
                .run();
        } else {
            Stmt(db_, "UPDATE tasks SET state = ? WHERE job_id = ? AND idx = ?")
                .bind(task_state::kLeased, job, task.task_index())
                .run();
        }
        Stmt(db_, "INSERT INTO attempts (job_id, task_idx, worker_id, state, leased_ms) VALUES (?, ?, ?, ?, ?)")
            .bind(job, task.task_index(), worker, attempt_state::kLeased, nowMs)
            .run();
        attempts.push_back(sqlite3_last_insert_rowid(db_));
    }
    tx.commit();
    return attempts;
}

void Store::endAttempt(int64_t attempt, const std::string &state, const std::string &error, int64_t nowMs) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    Stmt(db_, "UPDATE attempts SET state = ?, error = ?, finished_ms = ? WHERE id = ?")
        .bind(state, error, nowMs, attempt)
        .run();
    Stmt(db_,
         "UPDATE tasks SET state = ? WHERE state = ? AND (job_id, idx) = "
         "(SELECT job_id, task_idx FROM attempts WHERE id = ?)")
        .bind(task_state::kPending, task_state::kLeased, attempt)
        .run();
    tx.commit();
}

void Store::cancelAttempts(int64_t job, int64_t nowMs) {
    const std::lock_guard<std::mutex> lock(mu_);
    Stmt(db_, "UPDATE attempts SET state = ?, finished_ms = ? WHERE job_id = ? AND state = ?")
        .bind(attempt_state::kCancelled, nowMs, job, attempt_state::kLeased)
        .run();
}

void Store::ignoreAttempt(int64_t attempt, int64_t nowMs) {
    const std::lock_guard<std::mutex> lock(mu_);
    Stmt(db_,
         "UPDATE attempts SET state = ?, finished_ms = ?, error = 'late result of a superseded attempt' "
         "WHERE id = ?")
        .bind(attempt_state::kIgnored, nowMs, attempt)
        .run();
}

void Store::acceptResult(int64_t job, const std::vector<int64_t> &tasks, const std::vector<int64_t> &attempts,
                         const std::string &file, uint64_t bytes, const TaskStats &stats, int64_t nowMs) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    Stmt attempt(db_, "UPDATE attempts SET state = ?, finished_ms = ? WHERE id = ?");
    Stmt accept(db_, "UPDATE tasks SET state = ? WHERE job_id = ? AND idx = ?");
    Stmt insert(db_,
                "INSERT INTO results (job_id, task_idx, attempt_id, file, bytes, stats, accepted_ms) VALUES (?, ?, ?, "
                "?, ?, ?, ?)");
    for (size_t i = 0; i < attempts.size(); ++i) {
        const int64_t t = tasks.at(i);
        attempt.bind(attempt_state::kCompleted, nowMs, attempts[i]).run();
        accept.bind(task_state::kAccepted, job, t).run();
        insert.bind(job, t, attempts[i], file, i == 0 ? bytes : 0, serialize(i == 0 ? stats : TaskStats()), nowMs)
            .run();
    }
    tx.commit();
}

void Store::commitCheckpoint(const Job &job, int64_t fromTask, int64_t mergedTasks, const std::string &file,
                             int64_t nowMs) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    setJobState(job.id(), job);
    Stmt(db_, "UPDATE jobs SET merged_tasks = ?, checkpoint = ? WHERE id = ?").bind(mergedTasks, file, job.id()).run();
    Stmt(db_, "UPDATE tasks SET state = ? WHERE job_id = ? AND idx >= ? AND idx < ?")
        .bind(task_state::kMerged, job.id(), fromTask, mergedTasks)
        .run();
    Stmt insert(db_, "INSERT INTO merges (job_id, task_idx, checkpoint, merged_ms) VALUES (?, ?, ?, ?)");
    for (int64_t t = fromTask; t < mergedTasks; ++t) {
        insert.bind(job.id(), t, file, nowMs).run();
    }
    tx.commit();
}

void Store::discardResult(int64_t job, int64_t task) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    Stmt(db_, "DELETE FROM results WHERE job_id = ? AND task_idx = ?").bind(job, task).run();
    Stmt(db_, "UPDATE tasks SET state = ? WHERE job_id = ? AND idx = ?").bind(task_state::kPending, job, task).run();
    tx.commit();
}

std::vector<std::string> Store::rewindJob(int64_t job) {
    const std::lock_guard<std::mutex> lock(mu_);
    Transaction tx(db_);
    constexpr const char *kMerged =
        "FROM results WHERE job_id = ? AND task_idx IN (SELECT idx FROM tasks WHERE "
        "job_id = ? AND state = ?)";
    std::vector<std::string> files;
    Stmt q(db_, (std::string("SELECT file ") + kMerged).c_str());
    q.bind(job, job, task_state::kMerged);
    while (q.step()) files.push_back(q.text(0));
    Stmt(db_, (std::string("DELETE ") + kMerged).c_str()).bind(job, job, task_state::kMerged).run();
    Stmt(db_, "UPDATE tasks SET state = ? WHERE job_id = ? AND state = ?")
        .bind(task_state::kPending, job, task_state::kMerged)
        .run();
    Stmt(db_, "DELETE FROM merges WHERE job_id = ?").bind(job).run();
    Stmt(db_, "UPDATE jobs SET merged_tasks = 0, checkpoint = '' WHERE id = ?").bind(job).run();
    tx.commit();
    return files;
}

void Store::blocklist(int64_t job, const std::string &worker, const std::string &reason) {
    const std::lock_guard<std::mutex> lock(mu_);
    Stmt(db_, "INSERT OR IGNORE INTO blocklist (job_id, worker_id, reason) VALUES (?, ?, ?)")
        .bind(job, worker, reason)
        .run();
}

void Store::saveWorker(const WorkerInfo &w) {
    const std::lock_guard<std::mutex> lock(mu_);
    Stmt(db_, "INSERT OR REPLACE INTO workers (id, info) VALUES (?, ?)").bind(w.id(), serialize(w)).run();
}

std::vector<StoredJob> Store::loadJobs() {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<StoredJob> jobs;
    Stmt q(db_, "SELECT record, merged_tasks, checkpoint FROM jobs ORDER BY id");
    while (q.step()) {
        StoredJob j;
        if (!j.record.ParseFromString(q.text(0))) throw std::runtime_error("store: corrupt job record");
        j.mergedTasks = q.integer(1);
        j.checkpoint = q.text(2);
        jobs.push_back(std::move(j));
    }
    return jobs;
}

std::vector<StoredTask> Store::loadTasks(int64_t job) {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<StoredTask> tasks;
    Stmt q(db_, "SELECT idx, work, state FROM tasks WHERE job_id = ? ORDER BY idx");
    q.bind(job);
    while (q.step()) {
        StoredTask t;
        t.index = q.integer(0);
        if (!t.work.ParseFromString(q.text(1))) throw std::runtime_error("store: corrupt task record");
        t.state = q.text(2);
        tasks.push_back(std::move(t));
    }
    return tasks;
}

std::vector<StoredAttempt> Store::loadAttempts(int64_t job) {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<StoredAttempt> attempts;
    Stmt q(db_, "SELECT id, task_idx, worker_id, state FROM attempts WHERE job_id = ? ORDER BY id");
    q.bind(job);
    while (q.step()) attempts.push_back({q.integer(0), q.integer(1), q.text(2), q.text(3)});
    return attempts;
}

std::vector<StoredResult> Store::loadUnmergedResults(int64_t job) {
    return loadResults(
        "SELECT r.task_idx, r.attempt_id, r.file, r.stats FROM results r JOIN tasks t "
        "ON t.job_id = r.job_id AND t.idx = r.task_idx WHERE r.job_id = ? AND t.state = ? "
        "ORDER BY r.task_idx",
        job, task_state::kAccepted);
}

std::vector<StoredResult> Store::loadResults(int64_t job, int64_t toTask) {
    return loadResults(
        "SELECT task_idx, attempt_id, file, stats FROM results WHERE job_id = ? AND task_idx < ? "
        "ORDER BY task_idx",
        job, toTask);
}

template <class Arg>
std::vector<StoredResult> Store::loadResults(const char *sql, int64_t job, Arg arg) {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<StoredResult> results;
    Stmt q(db_, sql);
    q.bind(job, arg);
    while (q.step()) {
        StoredResult r{q.integer(0), q.integer(1), q.text(2), {}};
        if (!r.stats.ParseFromString(q.text(3))) throw std::runtime_error("store: corrupt result record");
        results.push_back(std::move(r));
    }
    return results;
}

std::vector<std::string> Store::loadBlocklist(int64_t job) {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<std::string> workers;
    Stmt q(db_, "SELECT worker_id FROM blocklist WHERE job_id = ? ORDER BY worker_id");
    q.bind(job);
    while (q.step()) workers.push_back(q.text(0));
    return workers;
}

std::vector<WorkerInfo> Store::loadWorkers() {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<WorkerInfo> workers;
    Stmt q(db_, "SELECT info FROM workers ORDER BY id");
    while (q.step()) {
        WorkerInfo w;
        if (!w.ParseFromString(q.text(0))) throw std::runtime_error("store: corrupt worker record");
        workers.push_back(std::move(w));
    }
    return workers;
}

}  // namespace pf::master
