// Master: scheduling. Workers register and ask for work; pickTask gives each the highest-priority job
// it may work on and nextTaskFor that job's next task (a retry first, on another worker when one could
// take it, else a new task while mayIssue allows); leases are renewed by heartbeats, and failed or
// expired attempts go back to the queue and count towards blocklists. The reaper expires leases and
// lost workers, closes time budgets and hands finished jobs to the merger (merger.cpp).
// Everything here runs under mu_, but the reaper's calls into the film side, which take the film mutex
// with mu_ released.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <random>

#include "farm/convert.h"
#include "farm/rpc.h"
#include "render/image_task.h"
#include "runtime.h"

namespace pf::master {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

std::string newWorkerId() {
    std::random_device rd;
    std::uniform_int_distribution<int> hex(0, 15);
    std::string id = "w-";
    for (int i = 0; i < 12; ++i) id += "0123456789abcdef"[hex(rd)];
    return id;
}

}  // namespace

v1::RegisterReply Master::registerWorker(const v1::RegisterRequest &req, const std::string &peer) {
    const std::lock_guard<std::mutex> lock(mu_);
    std::string id = req.worker_id();
    if (id.empty() || !workers_.count(id)) {
        id = newWorkerId();
        auto w = std::make_unique<WorkerRuntime>();
        w->info.set_id(id);
        w->info.set_registered_unix_ms(unixMs());
        workers_.emplace(id, std::move(w));
    }
    WorkerRuntime &w = *workers_.at(id);
    w.info.set_name(req.name().substr(0, 256));
    w.info.set_version(req.version().substr(0, 64));
    w.info.set_cores(req.cores());
    w.info.set_threads(req.threads());
    w.info.clear_algorithms();
    for (const auto &a : req.algorithms()) w.info.add_algorithms(a.substr(0, 64));
    w.info.set_peer(peer);
    w.info.set_state(v1::WORKER_IDLE);
    w.info.set_last_seen_unix_ms(unixMs());
    w.lastSeen = Clock::now();
    w.draining = false;
    store_.saveWorker(w.info);
    spdlog::info("worker={}: registered: name '{}', version {}, {} threads of {} cores, peer {}", id, w.info.name(),
                 w.info.version(), w.info.threads(), w.info.cores(), peer);
    workChanged_.notify_all();
    v1::RegisterReply reply;
    reply.set_worker_id(id);
    reply.set_lease_ms(cfg_.leaseTime.count());
    reply.set_heartbeat_ms(cfg_.heartbeat.count());
    reply.set_max_message_bytes(static_cast<uint64_t>(cfg_.maxMessageBytes));
    return reply;
}

std::vector<v1::TaskSpec> Master::lease(const std::string &worker, std::chrono::milliseconds wait, int maxTasks) {
    const auto until = Clock::now() + std::min<std::chrono::milliseconds>(wait, std::chrono::seconds(30));
    std::unique_lock<std::mutex> lock(mu_);
    for (;;) {
        const auto it = workers_.find(worker);
        if (it == workers_.end()) throw UnknownWorker("unknown worker '" + worker + "'");
        WorkerRuntime &w = *it->second;
        w.lastSeen = Clock::now();
        w.info.set_last_seen_unix_ms(unixMs());
        if (w.info.state() == v1::WORKER_LOST) w.info.set_state(v1::WORKER_IDLE);
        if (w.draining || stopping_) return {};
        if (auto task = pickTask(w)) {
            std::vector<v1::TaskSpec> tasks{std::move(*task)};
            // A batch (summed by the worker, so that the master decodes and merges it once) holds tasks of one
            // kind in a row: the master merges in task order, and a chain job's tasks merge by kind. A chain
            // job's row passes over the direct tasks between its chain tasks: they go to the next request (batchRow).
            // Cutting the row there instead (one per 400 chain tasks at 1024² once grown, render/chain_job.h) left
            // 358 chain tasks per chain result where 8 fake workers asked for 1024; passing them, 918 (bench_farm
            // part 6).
            JobRuntime &j = *jobs_.at(tasks.front().job_id());
            const int64_t first = tasks.front().task_index();
            const size_t most = batchable(j, first) ? batchLimit(j, maxTasks) : 1;
            std::vector<int64_t> following, passed;
            for (int64_t want = first + 1;
                 1 + following.size() < most && batchMayGrow(j, first, 1 + following.size(), w.info.threads());
                 ++want) {
                const std::optional<int64_t> next = nextTaskFor(j, w);
                if (!next) break;
                if (*next == want && passedInRow(j, want)) {
                    passed.push_back(want);
                    continue;
                }
                if (*next != want || !batchable(j, *next)) {
                    j.retry.insert(*next);  // issued but not in the batch's row: the next request takes it
                    break;
                }
                following.push_back(want);
            }
            j.retry.insert(passed.begin(), passed.end());
            if (!following.empty()) {
                try {
                    for (v1::TaskSpec &t : leaseIndices(j, w, following)) tasks.push_back(std::move(t));
                } catch (const StorageError &) {
                    // The first task's lease stands; the others went back to the queue.
                }
            }
            return tasks;
        }
        if (workChanged_.wait_until(lock, until) == std::cv_status::timeout) return {};
    }
}

std::optional<v1::TaskSpec> Master::pickTask(WorkerRuntime &w) {
    std::vector<JobRuntime *> order;
    for (auto &[id, j] : jobs_)
        if (isActive(j->record.state())) order.push_back(j.get());
    std::stable_sort(order.begin(), order.end(), [](const JobRuntime *a, const JobRuntime *b) {
        return a->record.spec().priority() > b->record.spec().priority();
    });
    for (JobRuntime *jp : order) {
        JobRuntime &j = *jp;
        if (!mayRun(j, w)) continue;
        const std::optional<int64_t> index = nextTaskFor(j, w);
        if (!index) continue;
        return std::move(leaseIndices(j, w, {*index}).front());
    }
    return std::nullopt;
}

std::vector<v1::TaskSpec> Master::leaseIndices(JobRuntime &j, WorkerRuntime &w, const std::vector<int64_t> &indices) {
    std::vector<v1::TaskSpec> specs;
    std::vector<bool> isNew;
    for (const int64_t index : indices) {
        const TaskRuntime &t = j.tasks[static_cast<size_t>(index)];
        isNew.push_back(t.attempt == 0 && t.failures == 0);
        v1::TaskSpec &spec = specs.emplace_back(t.work);
        spec.set_job_id(j.record.id());
        *spec.mutable_job() = j.record.spec();
        spec.set_scene_file(j.record.scene_file());
    }
    const int64_t now = unixMs();
    std::vector<int64_t> attempts;
    try {
        attempts = store_.leaseTasks(j.record.id(), specs, isNew, w.info.id(), now);
    } catch (const StorageError &) {
        j.retry.insert(indices.begin(), indices.end());  // not leased: the next request takes them again
        throw;
    }
    for (size_t i = 0; i < indices.size(); ++i) {
        const int64_t index = indices[i], attempt = attempts[i];
        specs[i].set_attempt_id(attempt);
        TaskRuntime &t = j.tasks[static_cast<size_t>(index)];
        t.state = TaskRuntime::State::Leased;
        t.attempt = attempt;
        t.leased = Clock::now();
        j.attemptTask[attempt] = index;
        j.attemptWorker[attempt] = w.info.id();
        leases_[attempt] = {j.record.id(), index, w.info.id(), Clock::now() + cfg_.leaseTime};
        w.attempts.insert(attempt);
        spdlog::info("job={} task={} attempt={} worker={}: leased, {}", j.record.id(), index, attempt, w.info.id(),
                     farm::describeWork(specs[i]));
    }
    if (j.record.state() == v1::JOB_QUEUED) {
        j.record.set_state(v1::JOB_RUNNING);
        j.record.set_started_unix_ms(now);
        store_.saveJob(snapshot(j));
    }
    touch();
    return specs;
}

std::optional<int64_t> Master::nextTaskFor(JobRuntime &j, const WorkerRuntime &w) {
    for (const int64_t index : j.retry) {
        const TaskRuntime &t = j.tasks[static_cast<size_t>(index)];
        // Retries go to other workers when there are any that could take them.
        const bool otherCandidate = std::any_of(workers_.begin(), workers_.end(), [&](const auto &entry) {
            const WorkerRuntime &o = *entry.second;
            return &o != &w && o.info.state() != v1::WORKER_LOST && !o.draining && !j.blocklist.count(o.info.id()) &&
                   !t.failedOn.count(o.info.id());
        });
        if (t.failedOn.count(w.info.id()) && otherCandidate) continue;
        j.retry.erase(index);
        return index;
    }
    if (!mayIssue(j)) return std::nullopt;
    TaskRuntime t;
    const int64_t index = static_cast<int64_t>(j.tasks.size());
    if (j.chain) {
        // The chain job's tasks never change once issued: only its merged results and the normalizer,
        // which is immutable once `seeded`, are read here.
        t.work = chainTaskWork(*j.film.chain->job, static_cast<uint64_t>(index));
        if (startsPass(j, index)) j.passStartMs = unixMs();
    } else {
        t.work.mutable_image()->set_first_sample(j.nextFirstSample);
        t.work.mutable_image()->set_sample_count(j.partialTiles > 0 ? 1 : taskSize(j.record, j.nextFirstSample));
        if (j.partialTiles > 0) t.work.mutable_image()->set_tiles(j.partialTiles);
        j.nextFirstSample += t.work.image().sample_count();
    }
    t.work.set_task_index(index);
    j.tasks.push_back(std::move(t));
    if (j.partialTiles > 0) {
        spdlog::info("job={}: the last task is partial: one sample in {} tiles", j.record.id(), j.partialTiles);
        j.partialTiles = 0;
        closeTimeBudget(j);
    }
    return index;
}

void Master::closeTimeBudget(JobRuntime &j) {
    j.total = static_cast<int64_t>(j.tasks.size());
    store_.saveJob(snapshot(j));
    spdlog::info("job={}: time budget reached after {:.2f} s: {} tasks issued", j.record.id(),
                 (unixMs() - j.record.started_unix_ms()) / 1000.0, j.total);
    touch();
}

bool Master::batchable(const JobRuntime &j, int64_t index) {
    const v1::TaskSpec &work = j.tasks[static_cast<size_t>(index)].work;
    // A partial task is never batched: the merger merges an image batch as one task of all its samples.
    return j.chain ? work.has_chain() : work.image().tiles() == 0;
}

std::vector<int64_t> Master::batchRow(const JobRuntime &j, int64_t first, size_t count) {
    std::vector<int64_t> row{first};
    const auto issued = static_cast<int64_t>(j.tasks.size());
    for (int64_t t = first + 1; row.size() < count && t < issued; ++t)
        if (!passedInRow(j, t)) row.push_back(t);
    return row;
}

bool Master::passedInRow(const JobRuntime &j, int64_t index) {
    return j.chain && j.tasks[static_cast<size_t>(index)].work.has_image();
}

bool Master::mayRun(const JobRuntime &j, const WorkerRuntime &w) {
    const auto &algs = w.info.algorithms();
    return !j.blocklist.count(w.info.id()) &&
           (algs.empty() || std::find(algs.begin(), algs.end(), j.record.integrator()) != algs.end());
}

size_t Master::batchLimit(const JobRuntime &j, int maxTasks) {
    const int asked = maxTasks == farm::kAutoBatch ? batchGovernor_.batch() : maxTasks;
    auto most = static_cast<int64_t>(std::clamp(asked, 1, j.chain ? kMaxChainBatchTasks : kMaxBatchTasks));
    if (j.total > 0) {
        // A budget in tasks: a batch holds at most its worker's share of the tasks not yet issued (its first
        // task included), shared among the live workers that may run them. A master busy enough to batch long
        // would otherwise lease a whole job of chain tasks to its first worker while the others wait.
        int64_t live = 0;
        for (const auto &[id, other] : workers_)
            if (other->info.state() != v1::WORKER_LOST && !other->draining && mayRun(j, *other)) ++live;
        const int64_t left = j.total - static_cast<int64_t>(j.tasks.size()) + 1;
        most = std::min(most, std::max<int64_t>(1, (left + live - 1) / std::max<int64_t>(live, 1)));
    }
    return static_cast<size_t>(most);
}

bool Master::batchMayGrow(const JobRuntime &j, int64_t firstTask, size_t batchTasks, int threads) const {
    if (j.total > 0) return true;  // a budget in samples: every task is issued anyway
    // Under a time budget the result leaves when the batch's last task is done. The worker renders image tasks
    // one after another, so the next one ends when the batch's samples and its own are rendered; chain tasks
    // run one per thread. With no task time measured yet the batch holds one task (a batch of 8 whole-image
    // tasks issued blind ran a 20 s job for 95 s).
    if (j.taskCount == 0) return false;
    const double elapsed = (unixMs() - j.record.started_unix_ms()) / 1000.0;
    const double budget = j.record.spec().budget().time_seconds();
    double seconds = 0;
    if (j.chain) {
        const auto perThread = static_cast<size_t>(std::max(threads, 1));
        seconds = j.expectedSeconds(0) * static_cast<double>((batchTasks + perThread) / perThread);
        // A chain batch also holds at most a quarter of the time left. Its passes are issued at its lease and
        // merged at its end, so the time since the last pass started, by which mayIssue decides whether another
        // pass fits, is the batch's length. Without this bound batches of 48 tasks closed a 30 s job 4.6 s early
        // (erpt at 1024², one 2-thread worker, the governor forced to grow).
        if (seconds > (budget - elapsed) / 4) return false;
    } else {
        int64_t spp = taskSize(j.record, j.nextFirstSample);
        for (size_t i = 0; i < batchTasks; ++i)
            spp += j.tasks[static_cast<size_t>(firstTask) + i].work.image().sample_count();
        seconds = j.expectedSeconds(spp);
    }
    return elapsed + seconds + j.expectedOverhead() <= budget;
}

bool Master::mayIssue(JobRuntime &j) {
    const int64_t issued = static_cast<int64_t>(j.tasks.size());
    // A chain job's seeding and direct tasks are all issued; its chain tasks wait for b̂.
    if (j.chain && (issued < j.chainFirst || !j.seeded)) return issued < j.chainFirst;
    if (j.total > 0) return issued < j.total;
    if (issued == j.chainFirst) return true;  // a time budget runs at least one task (of chains)
    // The clock decides whether another whole task is issued, never when one stops: issue while the
    // expected end of a new task is within the budget. Burst jobs are unbiased only over whole passes
    // (render/burst.h): a pass once started is issued whole, and the next starts if the last one's time
    // since its first task was issued (at least a task's time) still fits.
    if (j.chain && !startsPass(j, issued)) return true;
    const int64_t nextSpp = j.chain ? 0 : taskSize(j.record, j.nextFirstSample);
    // Before any result tells the job's pace, image tasks go out blind only at the smallest size: to many
    // workers at once, the sequence would otherwise hand out tasks far too long for the budget.
    if (j.taskCount == 0 && !j.chain && nextSpp > taskSize(j.record, 0)) return false;
    const double elapsed = (unixMs() - j.record.started_unix_ms()) / 1000.0;
    // A task ends for the job when it is merged: its transfer and merge come after its rendering.
    const double overhead = j.expectedOverhead();
    double estimate = j.expectedSeconds(nextSpp) + overhead;
    if (j.chain && j.film.chain->job->tasksPerPass() > 1 && j.passStartMs > 0)
        estimate = std::max(estimate, (unixMs() - j.passStartMs) / 1000.0);
    const double budget = j.record.spec().budget().time_seconds();
    if (elapsed + estimate <= budget) return true;
    // An image job whose next whole task no longer fits ends with a partial one: one sample in as many of the
    // film's tiles as the time left holds at one worker's pace, by what those tiles cost in the last whole task
    // (render/image_task.h; the merger adds it where it covers a pixel's whole filter footprint). Without it a
    // 1024² BDPT job, whose tasks are one sample per pixel of about 5 s each, left up to a task's time of its
    // budget unused on every worker.
    if (!j.chain && j.taskCount > 0) {
        j.partialTiles = timedPartialTiles(budget - overhead, elapsed, ImageTask{0, 1}, j.expectedSeconds(1),
                                           filmTiles(*j.film.film), j.tileSeconds);
        if (j.partialTiles > 0) return true;
    }
    closeTimeBudget(j);
    return false;
}

std::vector<int64_t> Master::heartbeat(const std::string &worker, const std::vector<int64_t> &attempts, bool draining) {
    const std::lock_guard<std::mutex> lock(mu_);
    const auto it = workers_.find(worker);
    if (it == workers_.end()) throw UnknownWorker("unknown worker '" + worker + "'");
    WorkerRuntime &w = *it->second;
    w.lastSeen = Clock::now();
    w.info.set_last_seen_unix_ms(unixMs());
    if (draining && !w.draining) spdlog::info("worker={}: draining", worker);
    w.draining = draining;
    std::vector<int64_t> lost;
    for (const int64_t a : attempts) {
        const auto l = leases_.find(a);
        if (l != leases_.end() && l->second.worker == worker) {
            l->second.deadline = Clock::now() + cfg_.leaseTime;
        } else if (!w.delivered.count(a)) {
            lost.push_back(a);
        }
    }
    w.delivered.clear();
    if (w.info.state() == v1::WORKER_LOST) w.info.set_state(v1::WORKER_IDLE);
    return lost;
}

void Master::countFailure(JobRuntime &j, const std::string &worker, const std::string &why) {
    if (++j.failuresByWorker[worker] < cfg_.maxFailuresPerWorker || !j.blocklist.insert(worker).second) return;
    const std::string reason = std::to_string(j.failuresByWorker[worker]) + " failures, the last: " + why;
    store_.blocklist(j.record.id(), worker, reason);
    spdlog::warn("job={} worker={}: blocklisted for this job after {}", j.record.id(), worker, reason);
}

void Master::requeue(JobRuntime &j, int64_t task, const std::string &worker, const std::string &state,
                     const std::string &error, int64_t attempt) {
    store_.endAttempt(attempt, state, error, unixMs());
    leases_.erase(attempt);
    if (const auto w = workers_.find(worker); w != workers_.end()) w->second->attempts.erase(attempt);
    TaskRuntime &t = j.tasks[static_cast<size_t>(task)];
    t.state = TaskRuntime::State::Pending;
    j.retry.insert(task);
    if (state != attempt_state::kReleased) countFailure(j, worker, error);
    touch();
    workChanged_.notify_all();
}

void Master::fail(const std::string &worker, int64_t attempt, const std::string &error, bool released) {
    const std::lock_guard<std::mutex> lock(mu_);
    const auto l = leases_.find(attempt);
    if (l == leases_.end() || l->second.worker != worker) return;  // expired or superseded already
    JobRuntime &j = *jobs_.at(l->second.job);
    const int64_t task = l->second.task;
    const std::string message = error.substr(0, 4096);
    if (released) {
        // Never started: another worker takes it now rather than after its lease expires.
        spdlog::info("job={} task={} attempt={} worker={}: given back unstarted: {}", j.record.id(), task, attempt,
                     worker, message);
        ++counters_.attemptsReleased;
        requeue(j, task, worker, attempt_state::kReleased, message, attempt);
        return;
    }
    spdlog::warn("job={} task={} attempt={} worker={}: failed: {}", j.record.id(), task, attempt, worker, message);
    TaskRuntime &t = j.tasks[static_cast<size_t>(task)];
    ++t.failures;
    t.failedOn.insert(worker);
    ++j.failedAttempts;
    ++counters_.attemptsFailed;
    requeue(j, task, worker, attempt_state::kFailed, message, attempt);
    if (t.failures >= cfg_.maxFailuresPerTask)
        setState(j, v1::JOB_FAILED,
                 "task " + std::to_string(task) + " failed " + std::to_string(t.failures) + " times; last: " + message);
}

std::string Master::checkAttempt(const std::string &worker, int64_t attempt) const {
    const std::lock_guard<std::mutex> lock(mu_);
    for (const auto &[id, j] : jobs_) {
        const auto a = j->attemptTask.find(attempt);
        if (a == j->attemptTask.end()) continue;
        if (j->attemptWorker.at(attempt) != worker)
            return "attempt " + std::to_string(attempt) + " was not leased to worker '" + worker.substr(0, 64) + "'";
        const TaskRuntime &t = j->tasks[static_cast<size_t>(a->second)];
        if (t.attempt != attempt || t.state == TaskRuntime::State::Accepted || t.state == TaskRuntime::State::Merged)
            return "superseded: task " + std::to_string(a->second) + " was given to another attempt";
        if (!isActive(j->record.state()))
            return "job " + std::to_string(id) + " is " + farm::stateName(j->record.state());
        return "";
    }
    return "unknown attempt " + std::to_string(attempt);
}

void Master::expire(Clock::time_point now) {
    for (auto it = leases_.begin(); it != leases_.end();) {
        const auto [attempt, lease] = *it++;
        if (lease.deadline > now) continue;
        JobRuntime &j = *jobs_.at(lease.job);
        spdlog::warn("job={} task={} attempt={} worker={}: lease expired", lease.job, lease.task, attempt,
                     lease.worker);
        requeue(j, lease.task, lease.worker, attempt_state::kExpired, "lease expired (no heartbeat)", attempt);
        ++j.expiredAttempts;
        ++counters_.attemptsExpired;
    }
    for (auto &[id, w] : workers_)
        if (w->info.state() != v1::WORKER_LOST && now - w->lastSeen > cfg_.leaseTime) {
            w->info.set_state(v1::WORKER_LOST);
            spdlog::warn("worker={}: lost (no contact for {} ms)", id, cfg_.leaseTime.count());
            touch();
            store_.saveWorker(w->info);
        }
}

void Master::reaperLoop() {
    const auto period = std::clamp<std::chrono::milliseconds>(cfg_.leaseTime / 10, std::chrono::milliseconds(20),
                                                              std::chrono::milliseconds(500));
    std::unique_lock<std::mutex> lock(mu_);
    while (!stopping_) {
        workChanged_.wait_for(lock, period);
        if (stopping_) break;
        try {
            expire(Clock::now());
        } catch (const StorageError &e) {
            // A full disk: what could not be recorded is expired again next period.
            spdlog::error("reaper: {}", e.what());
        }
        std::vector<JobRuntime *> complete, ended;
        for (auto &[id, j] : jobs_) {
            if (!isActive(j->record.state())) {
                if (j->filmOpen) ended.push_back(j.get());
                continue;
            }
            if (j->total == 0 && j->record.state() == v1::JOB_RUNNING)
                mayIssue(*j);  // closes a time budget even when no worker asks for work
            if (j->total > 0 && j->record.tasks().merged() == j->total) complete.push_back(j.get());
        }
        lock.unlock();
        for (JobRuntime *j : complete) {
            const std::lock_guard<std::mutex> filmLock(j->film.mu);
            finishIfComplete(*j);
        }
        for (JobRuntime *j : ended) {
            const std::lock_guard<std::mutex> filmLock(j->film.mu);
            closeFilm(*j);
        }
        lock.lock();
        for (JobRuntime *j : ended) j->filmOpen = false;
    }
}

}  // namespace pf::master
