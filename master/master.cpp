// Master: construction and teardown, and the status queries (jobs, workers, metrics), which copy what
// they report under mu_. The rest of the class lives in the files master.h lists.
#include "master.h"

#include <filesystem>

#include "farm/convert.h"
#include "film_files.h"
#include "runtime.h"

namespace pf::master {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

Master::Master(MasterConfig config)
    : cfg_(std::move(config)),
      bundles_((fs::create_directories(cfg_.dataDir), checkWritable(cfg_.dataDir),
                (fs::path(cfg_.dataDir) / "bundles").string()),
               cfg_.maxBundleBytes),
      store_((fs::path(cfg_.dataDir) / "store.sqlite").string()),
      batchGovernor_(cfg_.batchBusyShare, cfg_.batchWindow, kMaxChainBatchTasks) {
    recover();
    reaper_ = std::thread([this] { reaperLoop(); });
}

Master::~Master() {
    {
        const std::lock_guard<std::mutex> lock(mu_);
        stopping_ = true;
    }
    workChanged_.notify_all();
    jobChanged_.notify_all();
    reaper_.join();
}

std::string Master::jobDir(int64_t id) const { return (fs::path(cfg_.dataDir) / "jobs" / std::to_string(id)).string(); }

void Master::touch() {
    ++changes_;
    jobChanged_.notify_all();
}

std::optional<v1::Job> Master::job(int64_t id) const {
    const std::lock_guard<std::mutex> lock(mu_);
    const auto it = jobs_.find(id);
    if (it == jobs_.end()) return std::nullopt;
    return snapshot(*it->second);
}

std::vector<v1::Job> Master::jobs() const {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<v1::Job> out;
    for (const auto &[id, j] : jobs_) out.push_back(snapshot(*j));
    return out;
}

uint64_t Master::changeCount() const {
    const std::lock_guard<std::mutex> lock(mu_);
    return changes_;
}

uint64_t Master::waitForChange(uint64_t seen, std::chrono::milliseconds timeout) const {
    std::unique_lock<std::mutex> lock(mu_);
    jobChanged_.wait_for(lock, timeout, [&] { return changes_ > seen || stopping_; });
    return changes_;
}

std::vector<v1::WorkerInfo> Master::workers() const {
    const std::lock_guard<std::mutex> lock(mu_);
    std::vector<v1::WorkerInfo> out;
    for (const auto &[id, w] : workers_) {
        v1::WorkerInfo info = w->info;
        if (info.state() != v1::WORKER_LOST)
            info.set_state(w->draining ? v1::WORKER_DRAINING : w->attempts.empty() ? v1::WORKER_IDLE : v1::WORKER_BUSY);
        info.clear_attempt_ids();
        for (const int64_t a : w->attempts) info.add_attempt_ids(a);
        if (w->renderSeconds > 0) info.set_samples_per_second(static_cast<double>(w->samples) / w->renderSeconds);
        if (w->mutationSeconds > 0)
            info.set_mutations_per_second(static_cast<double>(w->mutations) / w->mutationSeconds);
        out.push_back(std::move(info));
    }
    return out;
}

MasterMetrics Master::metrics() const {
    const std::lock_guard<std::mutex> lock(mu_);
    MasterMetrics m = counters_;
    m.batchTasks = batchGovernor_.batch();
    for (const char *s : {task_state::kPending, task_state::kLeased, task_state::kAccepted, task_state::kMerged})
        m.tasksByState[s] = 0;
    for (const auto &[id, j] : jobs_) {
        ++m.jobsByState[farm::stateName(j->record.state())];
        for (const TaskRuntime &t : j->tasks)
            ++m.tasksByState[t.state == TaskRuntime::State::Pending    ? task_state::kPending
                             : t.state == TaskRuntime::State::Leased   ? task_state::kLeased
                             : t.state == TaskRuntime::State::Accepted ? task_state::kAccepted
                                                                       : task_state::kMerged];
    }
    m.workers = static_cast<int64_t>(workers_.size());
    for (const auto &[id, w] : workers_) m.workersAlive += w->info.state() != v1::WORKER_LOST;
    const int64_t since =
        std::chrono::duration_cast<std::chrono::seconds>(Clock::now().time_since_epoch()).count() - 59;
    uint64_t recent = 0;
    for (const auto &[t, n] : recentSamples_)
        if (t >= since) recent += n;
    m.samplesPerSecond = static_cast<double>(recent) / 60.0;
    return m;
}

}  // namespace pf::master
