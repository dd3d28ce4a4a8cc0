#include "worker.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <sstream>
#include <thread>
#include <tuple>

#include "cpu_quota.h"
#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/convert.h"
#include "farm/hash.h"
#include "farm/job_setup.h"
#include "render/chain_job.h"
#include "render/seeding.h"

namespace pf::worker {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

bool retryable(const grpc::Status &s) {
    return s.error_code() == grpc::StatusCode::UNAVAILABLE || s.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED ||
           s.error_code() == grpc::StatusCode::CANCELLED;
}

}  // namespace

Worker::Worker(WorkerConfig config)
    : cfg_(std::move(config)),
      channel_(farm::makeChannel(cfg_.master, cfg_.tls, cfg_.maxMessageBytes)),
      stub_(v1::WorkerService::NewStub(channel_)),
      cache_(cfg_.cacheDir, std::numeric_limits<uint64_t>::max()) {}

Worker::~Worker() {
    stopThreads();
    if (heartbeatThread_.joinable()) heartbeatThread_.join();
    if (uploadThread_.joinable()) uploadThread_.join();
    for (std::thread &t : runners_)
        if (t.joinable()) t.join();
}

std::unique_ptr<grpc::ClientContext> Worker::context(std::chrono::milliseconds timeout) const {
    auto ctx = std::make_unique<grpc::ClientContext>();
    farm::setBearer(*ctx, cfg_.token);
    ctx->set_deadline(std::chrono::system_clock::now() + timeout);
    return ctx;
}

void Worker::heardFromMaster() { lastContact_ = std::chrono::steady_clock::now().time_since_epoch().count(); }

bool Worker::masterGone() const {
    const auto silent =
        std::chrono::steady_clock::now().time_since_epoch() - std::chrono::steady_clock::duration(lastContact_.load());
    return draining_ && silent > std::chrono::milliseconds(leaseMs_.load());
}

std::string Worker::workerId() const {
    const std::lock_guard<std::mutex> lock(mu_);
    return workerId_;
}

bool Worker::backoff(int &step) const {
    static thread_local std::mt19937 rng(std::random_device{}());
    const int ms = std::min(5000, 200 << std::min(step, 5));
    ++step;
    const auto until = std::chrono::steady_clock::now() +
                       std::chrono::milliseconds(std::uniform_int_distribution<int>(ms / 2, ms)(rng));
    // Sleeps in short steps so that a stop is noticed.
    while (std::chrono::steady_clock::now() < until && !stopping_ && !masterGone())
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return !stopping_ && !masterGone();
}

void Worker::registerWithMaster() {
    v1::RegisterRequest req;
    req.set_worker_id(workerId());
    req.set_name(cfg_.name);
    req.set_version(farm::kVersion);
    req.set_cores(availableCores());
    req.set_threads(cfg_.threads);
    std::stringstream names(integratorNames());
    for (std::string n; std::getline(names >> std::ws, n, ',');) req.add_algorithms(n);
    for (int step = 0;;) {
        v1::RegisterReply reply;
        const grpc::Status s = stub_->Register(context(std::chrono::seconds(10)).get(), req, &reply);
        if (s.ok()) {
            heardFromMaster();
            if (reply.lease_ms() > 0) leaseMs_ = reply.lease_ms();
            const std::lock_guard<std::mutex> lock(mu_);
            workerId_ = reply.worker_id();
            heartbeat_ = std::chrono::milliseconds(std::max<int64_t>(20, reply.heartbeat_ms()));
            cfg_.maxMessageBytes = static_cast<int>(std::min<uint64_t>(reply.max_message_bytes(), 1 << 30));
            spdlog::info("worker={}: registered with {}, {} threads, heartbeat {} ms", workerId_, cfg_.master,
                         cfg_.threads, heartbeat_.count());
            return;
        }
        if (!retryable(s)) throw std::runtime_error("registration refused: " + s.error_message());
        spdlog::warn("master {} unavailable ({}); retrying", cfg_.master, s.error_message());
        if (!backoff(step)) return;
    }
}

void Worker::hold(int64_t attempt) {
    const std::lock_guard<std::mutex> lock(mu_);
    held_.insert(attempt);
}

void Worker::release(int64_t attempt) {
    const std::lock_guard<std::mutex> lock(mu_);
    held_.erase(attempt);
    lost_.erase(attempt);
}

bool Worker::isLost(int64_t attempt) const {
    const std::lock_guard<std::mutex> lock(mu_);
    return lost_.count(attempt) != 0;
}

// Set under the mutex: a thread that has just found stopping_ false under it and is about to wait would
// otherwise miss this notification and wait forever (a draining worker whose master was stopped once hung
// here, joining its upload thread, in a loaded suite run).
void Worker::stopThreads() {
    {
        const std::lock_guard<std::mutex> lock(mu_);
        stopping_ = true;
    }
    changed_.notify_all();
}

void Worker::drain() {
    draining_ = true;
    const std::lock_guard<std::mutex> lock(mu_);
    if (leaseCall_) leaseCall_->TryCancel();
    changed_.notify_all();
}

int Worker::run() {
    registerWithMaster();
    heartbeatThread_ = std::thread([this] { heartbeatLoop(); });
    uploadThread_ = std::thread([this] { uploadLoop(); });
    for (int i = 0; i < cfg_.threads; ++i) runners_.emplace_back([this] { runnerLoop(); });
    const auto idle = [&] { return (queued_.empty() && running_ == 0) || stopping_; };
    while (!draining_ && !stopping_) {
        {
            // A lease is taken only when a thread is free for it.
            std::unique_lock<std::mutex> lock(mu_);
            changed_.wait(lock, [&] {
                return static_cast<int>(queued_.size()) + running_ < cfg_.threads || draining_ || stopping_;
            });
        }
        const std::vector<v1::TaskSpec> tasks = leaseTasks();
        if (tasks.empty()) continue;
        for (const v1::TaskSpec &t : tasks) hold(t.attempt_id());
        std::unique_lock<std::mutex> lock(mu_);
        if (tasks.front().has_image()) {
            // An image task renders on every thread: it waits for the single-threaded tasks in hand.
            changed_.wait(lock, idle);
            lock.unlock();
            if (tasks.size() == 1) {
                work(tasks.front(), cfg_.threads);
            } else {
                workBatch(tasks, cfg_.threads);
            }
        } else if (tasks.size() == 1) {
            queued_.push_back({tasks.front(), nullptr});
            changed_.notify_all();
        } else {
            std::vector<int64_t> attempts;
            for (const v1::TaskSpec &t : tasks) attempts.push_back(t.attempt_id());
            // Results wait for their turn while the tasks before them still run: tasks of about equal length on
            // `threads` threads keep fewer than `threads` waiting, and twice that means one task is slow.
            const auto batch =
                std::make_shared<ChainBatch>(std::move(attempts), 2 * static_cast<size_t>(std::max(cfg_.threads, 1)));
            for (size_t i = 0; i < tasks.size(); ++i) queued_.push_back({tasks[i], batch, i});
            changed_.notify_all();
        }
    }
    spdlog::info("worker={}: draining: finishing the tasks and uploads in progress", workerId());
    int abandoned = 0;
    {
        std::unique_lock<std::mutex> lock(mu_);
        changed_.wait(lock, idle);
        changed_.wait(lock, [&] { return (uploads_.empty() && !uploading_) || stopping_; });
        abandoned = abandoned_;
    }
    // Said before the threads are joined, so that a drain that never ends shows in the log whether it waited
    // for its tasks and uploads or for a thread (a suite run once saw a silent master's worker hang here).
    spdlog::info("worker={}: drain: tasks and uploads done ({} abandoned); stopping its threads", workerId(),
                 abandoned);
    stopThreads();
    heartbeatThread_.join();
    uploadThread_.join();
    for (std::thread &t : runners_) t.join();
    runners_.clear();
    if (abandoned_ > 0) {
        spdlog::error(
            "worker={}: drained without the master: {} result(s) not delivered, as {} has not answered "
            "for {} ms (a lease time; their tasks are another worker's now); exiting",
            workerId(), abandoned_, cfg_.master, leaseMs_.load());
        return 1;
    }
    spdlog::info("worker={}: drained", workerId());
    return 0;
}

std::vector<v1::TaskSpec> Worker::leaseTasks() {
    for (int step = 0; !draining_;) {
        v1::LeaseRequest req;
        req.set_worker_id(workerId());
        req.set_wait_ms(2000);
        req.set_max_tasks(cfg_.batch);
        v1::LeaseReply reply;
        const auto ctx = context(std::chrono::seconds(30));
        {
            const std::lock_guard<std::mutex> lock(mu_);
            leaseCall_ = ctx.get();
        }
        spdlog::debug("worker={}: LeaseTask", req.worker_id());
        const grpc::Status s = stub_->LeaseTask(ctx.get(), req, &reply);
        {
            const std::lock_guard<std::mutex> lock(mu_);
            leaseCall_ = nullptr;
        }
        if (!retryable(s)) heardFromMaster();
        if (s.ok()) {
            std::vector<v1::TaskSpec> tasks;
            if (reply.has_task()) tasks.push_back(std::move(*reply.mutable_task()));
            for (v1::TaskSpec &t : *reply.mutable_more()) tasks.push_back(std::move(t));
            return tasks;
        }
        if (draining_) return {};
        if (s.error_code() == grpc::StatusCode::NOT_FOUND) {
            registerWithMaster();  // the master forgot this worker (a new store)
        } else if (!retryable(s)) {
            throw std::runtime_error("lease refused: " + s.error_message());
        } else {
            spdlog::warn("worker={}: master unavailable ({}); retrying", workerId(), s.error_message());
            if (!backoff(step)) return {};
        }
    }
    return {};
}

void Worker::runnerLoop() {
    for (;;) {
        std::unique_lock<std::mutex> lock(mu_);
        changed_.wait(lock, [&] { return !queued_.empty() || stopping_; });
        if (queued_.empty()) return;
        const Queued q = std::move(queued_.front());
        queued_.pop_front();
        ++running_;
        lock.unlock();
        if (draining_) {
            // A draining worker finishes what it started and gives the rest back, so that a long batch (up to
            // 1024 chain tasks) does not hold up its exit; the runs its finished tasks complete leave now.
            failTask(q.task.attempt_id(), "the worker is draining", true);
            if (q.batch) uploadRuns(q.batch->finish(q.slot, std::nullopt, 0));
        } else if (q.batch) {
            workInBatch(q);
        } else {
            work(q.task, 1);
        }
        lock.lock();
        --running_;
        changed_.notify_all();
    }
}

bool Worker::mayRender(const v1::TaskSpec &task) {
    spdlog::info("job={} task={} attempt={} worker={}: rendering {}", task.job_id(), task.task_index(),
                 task.attempt_id(), workerId(), farm::describeWork(task));
    if (!cfg_.failEveryTask) return true;
    failTask(task.attempt_id(), "injected fault (--fail-every-task)");
    return false;
}

bool Worker::keepResult(const v1::TaskSpec &task) {
    if (!isLost(task.attempt_id())) return true;
    spdlog::warn("job={} task={} attempt={}: lease lost while rendering; result dropped", task.job_id(),
                 task.task_index(), task.attempt_id());
    release(task.attempt_id());
    return false;
}

void Worker::queueUpload(Result result) {
    // Results wait while earlier ones upload; rendering the next tasks overlaps the uploads.
    std::unique_lock<std::mutex> lock(mu_);
    changed_.wait(lock, [&] { return static_cast<int>(uploads_.size()) < cfg_.threads || stopping_; });
    uploads_.push_back(std::move(result));
    changed_.notify_all();
}

void Worker::work(const v1::TaskSpec &task, int threads) {
    const int64_t attempt = task.attempt_id();
    if (!mayRender(task)) return;
    std::optional<Result> result;
    try {
        const auto t0 = std::chrono::steady_clock::now();
        const std::shared_ptr<const Prepared> p = prepare(task);
        const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        result.emplace(runTask(*p, task, threads));
        result->loadSeconds = loadSeconds;
    } catch (const std::exception &e) {
        failTask(attempt, e.what());
        return;
    }
    if (keepResult(task)) queueUpload(std::move(*result));
}

void Worker::workBatch(const std::vector<v1::TaskSpec> &tasks, int threads) {
    // The tasks follow each other in their job; their blocks are summed in task order, as the master
    // would merge them. A task that fails or whose lease is lost ends the run before it.
    std::optional<ImageBlock> sum;
    Result run{};
    const auto flush = [&] {
        if (!sum) return;
        run.payload = farm::encodeBlock(*sum);
        queueUpload(std::move(run));
        sum.reset();
    };
    for (const v1::TaskSpec &task : tasks) {
        if (draining_) {
            flush();
            failTask(task.attempt_id(), "the worker is draining", true);
            continue;
        }
        if (!mayRender(task)) {
            flush();
            continue;
        }
        std::optional<ImageTaskResult> image;
        double loadSeconds = 0;
        try {
            const auto t0 = std::chrono::steady_clock::now();
            const std::shared_ptr<const Prepared> p = prepare(task);
            loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            image.emplace(renderImage(*p, task, threads));
        } catch (const std::exception &e) {
            failTask(task.attempt_id(), e.what());
            flush();
            continue;
        }
        if (!keepResult(task)) {
            flush();
            continue;
        }
        if (sum) {
            sum->merge(image->block);
            run.batch.push_back(task.attempt_id());
            run.samples += image->samples;
            run.rays += image->rays;
            run.seconds += image->seconds;
            run.loadSeconds += loadSeconds;
            for (size_t k = 0; k < run.tileSeconds.size() && k < image->tileSeconds.size(); ++k)
                run.tileSeconds[k] += image->tileSeconds[k];
        } else {
            sum.emplace(std::move(image->block));
            run = Result{task.attempt_id(), {}, {}, image->samples, image->rays, image->seconds, loadSeconds};
            run.tileSeconds = std::move(image->tileSeconds);
        }
    }
    flush();
}

void Worker::workInBatch(const Queued &q) {
    const v1::TaskSpec &task = q.task;
    std::optional<ChainResult> result;
    double loadSeconds = 0;
    if (mayRender(task)) {
        try {
            const auto t0 = std::chrono::steady_clock::now();
            const std::shared_ptr<const Prepared> p = prepare(task);
            loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            if (!task.has_chain()) throw std::runtime_error("a batch holds chain tasks only");
            result.emplace(runChain(*p, task));
        } catch (const std::exception &e) {
            failTask(task.attempt_id(), e.what());
        }
        if (result && !keepResult(task)) result.reset();
    }
    uploadRuns(q.batch->finish(q.slot, std::move(result), loadSeconds));
}

void Worker::uploadRuns(std::vector<ChainBatch::Run> runs) {
    for (ChainBatch::Run &run : runs) {
        const ChainResult &c = run.sum;
        Result r{run.attempts.front(),
                 {run.attempts.begin() + 1, run.attempts.end()},
                 farm::encodeChainResult(c),
                 c.mutations,
                 c.rays,
                 c.seconds,
                 run.loadSeconds};
        queueUpload(std::move(r));
    }
}

ChainResult Worker::runChain(const Prepared &p, const v1::TaskSpec &task) const {
    const auto *chain = dynamic_cast<const ChainIntegrator *>(p.integrator.get());
    if (!chain) throw std::runtime_error("integrator '" + p.integrator->name() + "' runs no chain tasks");
    return runChainTask(*p.scene, *chain, task.job().seed(), farm::fromProto(task.chain()));
}

ImageTaskResult Worker::renderImage(const Prepared &p, const v1::TaskSpec &task, int threads) const {
    const uint64_t seed = task.job().seed();
    const ImageTask image{task.image().first_sample(), task.image().sample_count(),
                          task.image().tiles() > 0 ? task.image().tiles() : -1};
    // A chain job's direct component renders with its own integrator, seed and numbers (render/chain_job.h).
    if (task.image().direct()) {
        const auto *chain = dynamic_cast<const ChainIntegrator *>(p.integrator.get());
        if (!chain || !chain->directIntegrator())
            throw std::runtime_error("integrator '" + p.integrator->name() + "' runs no direct tasks");
        return runDirectTask(*p.scene, *chain, seed, image, threads);
    }
    const auto *integrator = dynamic_cast<const SamplingIntegrator *>(p.integrator.get());
    if (!integrator) throw std::runtime_error("integrator '" + p.integrator->name() + "' does not run image tasks");
    return runImageTask(*p.scene, *integrator, seed, image, threads);
}

Worker::Result Worker::runTask(const Prepared &p, const v1::TaskSpec &task, int threads) const {
    const uint64_t seed = task.job().seed();
    const auto *chain = dynamic_cast<const ChainIntegrator *>(p.integrator.get());
    if ((task.has_seeding() || task.has_chain() || task.image().direct()) && !chain)
        throw std::runtime_error("integrator '" + p.integrator->name() + "' runs no seeding or chain tasks");
    Result r{task.attempt_id(), {}, {}, 0, 0, 0, 0};
    if (task.has_seeding()) {
        // The job's spp budget, as the master's ChainJob saw it (0: a time budget or the scene's sampleCount).
        const int64_t spp = task.job().budget().kind_case() == v1::Budget::kSpp ? task.job().budget().spp() : 0;
        const SeedingResult s = chain->runSeeding(*p.scene, spp, seed, farm::fromProto(task.seeding()));
        r.payload = farm::encodeSeedingResult(s);
        std::tie(r.samples, r.rays, r.seconds) = std::tuple(s.samples, s.rays, s.seconds);
    } else if (task.has_chain()) {
        const ChainResult c = runChain(p, task);
        r.payload = farm::encodeChainResult(c);
        std::tie(r.samples, r.rays, r.seconds) = std::tuple(c.mutations, c.rays, c.seconds);
    } else if (task.has_image()) {
        ImageTaskResult i = renderImage(p, task, threads);
        r.payload = farm::encodeBlock(i.block);
        std::tie(r.samples, r.rays, r.seconds) = std::tuple(i.samples, i.rays, i.seconds);
        r.tileSeconds = std::move(i.tileSeconds);
    } else {
        throw std::runtime_error("this worker cannot run the task kind it was given");
    }
    return r;
}

std::shared_ptr<const Worker::Prepared> Worker::prepare(const v1::TaskSpec &task) {
    // Everything that shapes the scene or the integrator, and nothing else, forms the cache key.
    v1::JobSpec keySpec;
    keySpec.set_bundle_hash(task.job().bundle_hash());
    keySpec.set_integrator(task.job().integrator());
    *keySpec.mutable_params() = task.job().params();
    *keySpec.mutable_defines() = task.job().defines();
    const std::string key = keySpec.SerializeAsString() + task.scene_file();
    const std::lock_guard<std::mutex> lock(prepareMu_);
    if (prepared_ && prepared_->key == key) return prepared_;
    prepared_.reset();
    if (!cache_.has(task.job().bundle_hash())) fetchBundle(task.job().bundle_hash());
    const v1::BundleManifest manifest = cache_.manifest(task.job().bundle_hash());
    if (manifest.scene_file() != task.scene_file())
        throw std::runtime_error("bundle " + task.job().bundle_hash() + " has no scene '" + task.scene_file() + "'");
    const auto t0 = std::chrono::steady_clock::now();
    auto p = std::make_shared<Prepared>(
        Prepared{key,
                 loadScene((fs::path(cache_.dir(task.job().bundle_hash())) / task.scene_file()).string(),
                           farm::toNameValues(task.job().defines())),
                 nullptr});
    p->integrator = makeIntegrator(*p->scene, task.job().integrator(), farm::toNameValues(task.job().params()));
    spdlog::info("job={}: scene {} loaded in {:.2f} s", task.job_id(), task.scene_file(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    prepared_ = std::move(p);
    return prepared_;
}

void Worker::fetchBundle(const std::string &hash) {
    for (int step = 0;;) {
        v1::FetchBundleRequest req;
        req.set_hash(hash);
        const auto ctx = context(std::chrono::minutes(30));
        auto reader = stub_->FetchBundle(ctx.get(), req);
        try {
            cache_.receive([&](v1::BundleChunk &c) { return reader->Read(&c); }, hash);
        } catch (const std::exception &e) {
            ctx->TryCancel();
            reader->Finish();
            throw std::runtime_error(std::string("bundle ") + hash + ": " + e.what());
        }
        const grpc::Status s = reader->Finish();
        if (s.ok()) {
            heardFromMaster();
            spdlog::info("bundle {}: cached", hash);
            return;
        }
        if (!retryable(s) || !backoff(step)) throw std::runtime_error("bundle " + hash + ": " + s.error_message());
    }
}

void Worker::failTask(int64_t attempt, const std::string &error, bool released) {
    if (released) {
        spdlog::info("attempt={} worker={}: given back: {}", attempt, workerId(), error);
    } else {
        spdlog::warn("attempt={} worker={}: failed: {}", attempt, workerId(), error);
    }
    for (int step = 0;;) {
        v1::FailTaskRequest req;
        req.set_worker_id(workerId());
        req.set_attempt_id(attempt);
        req.set_error(error);
        req.set_released(released);
        v1::FailTaskReply reply;
        const grpc::Status s = stub_->FailTask(context(std::chrono::seconds(10)).get(), req, &reply);
        if (!retryable(s)) heardFromMaster();
        if (s.ok() || !retryable(s) || isLost(attempt) || !backoff(step)) break;
    }
    release(attempt);
}

bool Worker::upload(const Result &r) {
    const std::string &payload = r.payload;
    const std::string hash = farm::hashHex64(payload);
    const size_t chunk = static_cast<size_t>(std::max(4096, cfg_.maxMessageBytes - 4096));
    const auto lost = [&] {
        return isLost(r.attempt) || std::any_of(r.batch.begin(), r.batch.end(), [&](int64_t a) { return isLost(a); });
    };
    for (int step = 0; !lost();) {
        v1::CompleteReply reply;
        const auto ctx = context(std::chrono::minutes(10));
        {
            const std::lock_guard<std::mutex> lock(mu_);
            uploadCall_ = ctx.get();
        }
        auto writer = stub_->CompleteTask(ctx.get(), &reply);
        v1::ResultChunk c;
        auto *h = c.mutable_header();
        h->set_worker_id(workerId());
        h->set_attempt_id(r.attempt);
        for (const int64_t a : r.batch) h->add_batch_attempt_ids(a);
        h->mutable_stats()->set_samples(r.samples);
        h->mutable_stats()->set_rays(r.rays);
        h->mutable_stats()->set_seconds(r.seconds);
        h->mutable_stats()->set_scene_load_seconds(r.loadSeconds);
        h->mutable_stats()->mutable_tile_seconds()->Add(r.tileSeconds.begin(), r.tileSeconds.end());
        h->set_payload_size(payload.size());
        h->set_payload_hash(hash);
        // A refused stream stops accepting writes; Finish() then says why.
        bool open = writer->Write(c);
        for (size_t off = 0; open && off < payload.size(); off += chunk) {
            c.set_data(payload.substr(off, chunk));
            open = writer->Write(c);
        }
        if (open) writer->WritesDone();
        const grpc::Status s = writer->Finish();
        {
            const std::lock_guard<std::mutex> lock(mu_);
            uploadCall_ = nullptr;
        }
        if (!retryable(s)) heardFromMaster();  // an answer, even a refusal
        if (s.ok()) {
            if (reply.accepted()) {
                spdlog::info("attempt={} worker={}: result accepted ({} bytes, {:.2f} s)", r.attempt, workerId(),
                             payload.size(), r.seconds);
            } else {
                spdlog::warn("attempt={} worker={}: result ignored: {}", r.attempt, workerId(), reply.reason());
            }
            return true;
        }
        if (!retryable(s)) {
            spdlog::error("attempt={} worker={}: result refused: {}", r.attempt, workerId(), s.error_message());
            return true;
        }
        spdlog::warn("attempt={}: master unavailable ({}); retrying the upload", r.attempt, s.error_message());
        if (!backoff(step)) {
            if (!masterGone()) return true;  // stopping
            spdlog::error(
                "attempt={} worker={}: draining, and the master {} has not answered for {} ms (a lease "
                "time): result abandoned",
                r.attempt, workerId(), cfg_.master, leaseMs_.load());
            return false;
        }
    }
    spdlog::warn("attempt={}: lease lost before the result was delivered", r.attempt);
    return true;
}

void Worker::uploadLoop() {
    for (;;) {
        std::unique_lock<std::mutex> lock(mu_);
        changed_.wait(lock, [&] { return !uploads_.empty() || stopping_; });
        if (uploads_.empty()) return;
        uploading_ = true;
        Result r = std::move(uploads_.front());
        uploads_.pop_front();
        changed_.notify_all();
        lock.unlock();
        if (cfg_.uploadDelaySeconds > 0)
            std::this_thread::sleep_for(std::chrono::duration<double>(cfg_.uploadDelaySeconds));
        const bool delivered = upload(r);
        release(r.attempt);
        for (const int64_t a : r.batch) release(a);
        lock.lock();
        abandoned_ += !delivered;
        uploading_ = false;
        changed_.notify_all();
    }
}

void Worker::heartbeatLoop() {
    for (;;) {
        std::chrono::milliseconds period;
        v1::HeartbeatRequest req;
        {
            std::unique_lock<std::mutex> lock(mu_);
            period = heartbeat_;
            if (changed_.wait_for(lock, period, [&] { return stopping_.load(); })) return;
            req.set_worker_id(workerId_);
            for (const int64_t a : held_) req.add_attempt_ids(a);
        }
        req.set_draining(draining_);
        v1::HeartbeatReply reply;
        const grpc::Status s = stub_->Heartbeat(context(period * 2).get(), req, &reply);
        if (!retryable(s)) heardFromMaster();
        if (masterGone()) {
            // A silent master (a partition rather than a refused connection) must not hold a draining
            // worker for an upload's whole deadline.
            const std::lock_guard<std::mutex> lock(mu_);
            if (uploadCall_) uploadCall_->TryCancel();
        }
        if (s.error_code() == grpc::StatusCode::NOT_FOUND) {
            registerWithMaster();
        } else if (s.ok()) {
            const std::lock_guard<std::mutex> lock(mu_);
            for (const int64_t a : reply.lost_attempt_ids()) {
                if (held_.count(a) && lost_.insert(a).second)
                    spdlog::warn("attempt={} worker={}: lease lost (expired or job ended)", a, workerId_);
            }
        }
    }
}

}  // namespace pf::worker
