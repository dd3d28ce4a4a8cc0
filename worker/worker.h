// The worker: registers with the master and pulls tasks. An image task renders on all its threads; seeding
// and chain tasks run one per thread (a chain is sequential), so the worker holds up to --threads of them
// at once, or a batch of chain tasks (chain_batch.h). Results stream back while the next tasks run. Leases
// are renewed by a heartbeat thread; scenes are cached by bundle hash (on disk) and the last loaded scene is
// kept in memory. When the master is away every call is retried with backoff, so a restarted master finds its
// workers again; a draining worker stops retrying once the master has not answered for a lease time (its
// tasks are then another worker's) and exits, reporting the results it could not deliver.
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
#include <vector>

#include "chain_batch.h"
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
    // Tasks leased at once and returned as one result (image tasks, or a chain job's chain tasks, merged here
    // in task order), so that the master decodes and merges one film for all of them. 1: a result per task,
    // whose merge on the master reproduces the embedded render bit for bit; a batch's sum rounds differently
    // (in the last bits).
    // farm::kAutoBatch: as many as the master chooses, which batches only while results keep it busy.
    int batch = farm::kAutoBatch;
    int maxMessageBytes = 4 << 20;  // until the master says otherwise
    // Test-only fault injection: report every leased task as failed without rendering it.
    bool failEveryTask = false;
    // Test-only: wait this long before each upload, as a slow link to the master would.
    double uploadDelaySeconds = 0;
};

class Worker {
public:
    explicit Worker(WorkerConfig config);
    ~Worker();
    Worker(const Worker &) = delete;
    Worker &operator=(const Worker &) = delete;

    // Works until drain() and the last upload finish. Returns the process exit code: 0, or 1 when the
    // worker drained without reaching the master and results were abandoned.
    int run();
    // Stops leasing; the task being rendered and the results being uploaded are finished first.
    void drain();

private:
    // Tells the heartbeat, upload and runner threads to stop (they exit once their current call or task ends).
    void stopThreads();
    struct Result {
        int64_t attempt;
        std::vector<int64_t> batch;  // the attempts of the tasks after `attempt`'s that the payload holds
        std::string payload;         // by task kind (see TaskSpec in common.proto)
        uint64_t samples, rays;
        double seconds;
        double loadSeconds;                   // preparing the scene for this task
        std::vector<float> tileSeconds = {};  // image tasks: ImageTaskResult::tileSeconds, summed over a batch
    };
    struct Prepared {
        std::string key;
        std::unique_ptr<Scene> scene;
        std::unique_ptr<Integrator> integrator;
    };

    void registerWithMaster();
    // A task, and with --batch the image tasks after it (empty: none now).
    std::vector<pathfarm::v1::TaskSpec> leaseTasks();
    // Runs a task (held already) on `threads` threads and queues its result for upload.
    void work(const pathfarm::v1::TaskSpec &task, int threads);
    // A single-threaded task waiting for a runner, and the batch of chain tasks it belongs to (null: none).
    struct Queued {
        pathfarm::v1::TaskSpec task;
        std::shared_ptr<ChainBatch> batch;
        size_t slot = 0;  // its place in the batch
    };
    // Runs a chain task of a batch on this thread, and queues the runs of the batch it completes for upload.
    void workInBatch(const Queued &q);
    // Runs a batch of image tasks (held already) one after another on `threads` threads, and queues each
    // run of them that follow each other (all, unless one failed or was lost) as one result.
    void workBatch(const std::vector<pathfarm::v1::TaskSpec> &tasks, int threads);
    // Logs the task; false (and the attempt reported or released) when it must not be rendered or its
    // result not be delivered: fault injection before, a lost lease after rendering.
    bool mayRender(const pathfarm::v1::TaskSpec &task);
    bool keepResult(const pathfarm::v1::TaskSpec &task);
    ImageTaskResult renderImage(const Prepared &p, const pathfarm::v1::TaskSpec &task, int threads) const;
    ChainResult runChain(const Prepared &p, const pathfarm::v1::TaskSpec &task) const;
    void queueUpload(Result result);
    Result runTask(const Prepared &p, const pathfarm::v1::TaskSpec &task, int threads) const;
    // Runs the queued single-threaded tasks (seeding, chains), one at a time.
    void runnerLoop();
    std::shared_ptr<const Prepared> prepare(const pathfarm::v1::TaskSpec &task);
    void fetchBundle(const std::string &hash);
    // Tells the master the attempt ended without a result: it failed, or (`released`) it is given back unstarted.
    void failTask(int64_t attempt, const std::string &error, bool released = false);
    // Queues the runs of a chain batch that are complete for upload, each as one result.
    void uploadRuns(std::vector<ChainBatch::Run> runs);
    // Delivers a result; false when it was abandoned (lease lost, refused, or the master gone while
    // draining).
    bool upload(const Result &r);
    void heartbeatLoop();
    void uploadLoop();

    std::string workerId() const;
    void hold(int64_t attempt);
    void release(int64_t attempt);
    bool isLost(int64_t attempt) const;
    // Sleeps the next backoff step (growing to a few seconds, with jitter); false when stopping, or when
    // draining and the master is gone, made further retries pointless.
    bool backoff(int &step) const;
    std::unique_ptr<grpc::ClientContext> context(std::chrono::milliseconds timeout) const;
    // The master answered a call.
    void heardFromMaster();
    // Draining, and the master has not answered for a lease time: by then it has expired this worker's
    // leases and given their tasks to others, so retrying would only delay the exit.
    bool masterGone() const;

    WorkerConfig cfg_;
    std::shared_ptr<grpc::Channel> channel_;
    std::unique_ptr<pathfarm::v1::WorkerService::Stub> stub_;
    farm::BundleStore cache_;
    std::mutex prepareMu_;  // one scene load at a time; guards prepared_
    std::shared_ptr<const Prepared> prepared_;

    mutable std::mutex mu_;
    std::condition_variable changed_;
    std::string workerId_;
    std::chrono::milliseconds heartbeat_{3000};
    std::atomic<int64_t> leaseMs_{10000};  // the master's lease time, from its registration reply
    // When the master last answered (steady clock, nanoseconds since its epoch).
    std::atomic<int64_t> lastContact_{std::chrono::steady_clock::now().time_since_epoch().count()};
    int abandoned_ = 0;  // results not delivered
    std::set<int64_t> held_, lost_;
    std::deque<Result> uploads_;
    bool uploading_ = false;
    std::deque<Queued> queued_;  // single-threaded tasks waiting for a runner
    int running_ = 0;            // single-threaded tasks running
    std::vector<std::thread> runners_;
    grpc::ClientContext *leaseCall_ = nullptr;   // cancelled by drain()
    grpc::ClientContext *uploadCall_ = nullptr;  // cancelled once draining and the master is gone
    std::atomic<bool> draining_{false}, stopping_{false};
    std::thread heartbeatThread_, uploadThread_;
};

}  // namespace pf::worker
