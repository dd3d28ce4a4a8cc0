// The worker: registers with the master, pulls one task at a time, renders it with all its threads and
// streams the film block back while it renders the next one. Leases are renewed by a heartbeat thread;
// scenes are cached by bundle hash (on disk) and the last loaded scene is kept in memory. When the
// master is away every call is retried with backoff, so a restarted master finds its workers again.
#pragma once
#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>

#include "farm/bundle.h"
#include "farm/rpc.h"
#include "integrators/integrator.h"
#include "pathfarm/v1/worker.grpc.pb.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace pf::worker {

struct WorkerConfig {
    std::string master = "127.0.0.1:7700";
    farm::TlsFiles tls;
    std::string token;
    std::string name;
    std::string cacheDir = "pathfarm-cache";
    int threads = 1;
    int maxMessageBytes = 4 << 20;  // until the master says otherwise
    // Test-only fault injection: report every leased task as failed without rendering it.
    bool failEveryTask = false;
};

// The cores this process may use: its CPU affinity, further limited by a cgroup CPU quota (containers).
int availableCores();

class Worker {
public:
    explicit Worker(WorkerConfig config);
    ~Worker();
    Worker(const Worker &) = delete;
    Worker &operator=(const Worker &) = delete;

    // Works until drain() and the last upload finish. Returns the process exit code.
    int run();
    // Stops leasing; the task being rendered and the results being uploaded are finished first.
    void drain();

private:
    struct Result {
        int64_t attempt;
        ImageTaskResult result;
        double loadSeconds;  // preparing the scene for this task
    };
    struct Prepared {
        std::string key;
        std::unique_ptr<Scene> scene;
        std::unique_ptr<Integrator> integrator;
    };

    void registerWithMaster();
    std::optional<pathfarm::v1::TaskSpec> leaseTask();
    void work(const pathfarm::v1::TaskSpec &task);
    const Prepared &prepare(const pathfarm::v1::TaskSpec &task);
    void fetchBundle(const std::string &hash);
    void failTask(int64_t attempt, const std::string &error);
    void upload(const Result &r);
    void heartbeatLoop();
    void uploadLoop();

    std::string workerId() const;
    void hold(int64_t attempt);
    void release(int64_t attempt);
    bool isLost(int64_t attempt) const;
    // Sleeps the next backoff step (growing to a few seconds, with jitter); false when draining made
    // further retries pointless.
    bool backoff(int &step) const;
    std::unique_ptr<grpc::ClientContext> context(std::chrono::milliseconds timeout) const;

    WorkerConfig cfg_;
    std::shared_ptr<grpc::Channel> channel_;
    std::unique_ptr<pathfarm::v1::WorkerService::Stub> stub_;
    farm::BundleStore cache_;
    std::optional<Prepared> prepared_;

    mutable std::mutex mu_;
    std::condition_variable changed_;
    std::string workerId_;
    std::chrono::milliseconds heartbeat_{3000};
    std::set<int64_t> held_, lost_;
    std::deque<Result> uploads_;
    bool uploading_ = false;
    grpc::ClientContext *leaseCall_ = nullptr;  // cancelled by drain()
    std::atomic<bool> draining_{false}, stopping_{false};
    std::thread heartbeatThread_, uploadThread_;
};

}  // namespace pf::worker
