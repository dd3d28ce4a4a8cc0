#include "master.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/convert.h"
#include "farm/error.h"
#include "farm/job_setup.h"
#include "farm/rpc.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace pf::master {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

int64_t unixMs() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
}

// Writes `data` to `path` through a temporary file and a rename, so that a reader (or a restarted
// master) sees either nothing or the whole file. With `durable` the data reaches the disk before the
// rename, for files that committed rows will name.
void writeFileAtomic(const fs::path &path, std::string_view data, bool durable) {
    const fs::path tmp = path.string() + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw std::runtime_error("cannot write " + tmp.string());
    for (size_t done = 0; done < data.size();) {
        const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ::close(fd);
            throw std::runtime_error("cannot write " + tmp.string());
        }
        done += static_cast<size_t>(n);
    }
    if ((durable && ::fsync(fd) != 0) | (::close(fd) != 0)) throw std::runtime_error("cannot write " + tmp.string());
    fs::rename(tmp, path);
}

bool isActive(v1::JobState s) { return s == v1::JOB_QUEUED || s == v1::JOB_RUNNING; }

std::string newWorkerId() {
    std::random_device rd;
    std::uniform_int_distribution<int> hex(0, 15);
    std::string id = "w-";
    for (int i = 0; i < 12; ++i) id += "0123456789abcdef"[hex(rd)];
    return id;
}

// Rejects what no scene or integrator could make sense of, before anything is loaded.
// Messages name files as the submitter knows them, relative to the scene's directory.
std::string relativeTo(const std::string &root, std::string msg) {
    for (size_t at; (at = msg.find(root)) != std::string::npos;) msg.erase(at, root.size());
    return msg;
}

void checkSpec(const JobSpec &spec, const MasterConfig &cfg) {
    constexpr int kMaxParams = 256;
    constexpr size_t kMaxText = 4096;
    if (spec.bundle_hash().empty()) throw farm::FarmError("job spec: bundle_hash is missing (upload the scene first)");
    if (spec.params_size() > kMaxParams || spec.defines_size() > kMaxParams)
        throw farm::FarmError("job spec: more than " + std::to_string(kMaxParams) + " parameters or definitions");
    for (const auto *list : {&spec.params(), &spec.defines()})
        for (const auto &p : *list)
            if (p.name().empty() || p.name().size() > kMaxText || p.value().size() > kMaxText)
                throw farm::FarmError("job spec: parameter '" + p.name().substr(0, 64) +
                                      "' has an empty or overlong name or value");
    if (spec.integrator().size() > kMaxText || spec.label().size() > kMaxText)
        throw farm::FarmError("job spec: overlong integrator name or label");
    if (spec.budget().has_spp() && (spec.budget().spp() < 1 || spec.budget().spp() > cfg.maxSpp))
        throw farm::FarmError("job spec: spp must be in [1, " + std::to_string(cfg.maxSpp) + "], got " +
                              std::to_string(spec.budget().spp()));
    if (spec.budget().has_time_seconds()) {
        const double t = spec.budget().time_seconds();
        if (!std::isfinite(t) || t <= 0 || t > cfg.maxTimeSeconds)
            throw farm::FarmError("job spec: time budget must be in (0, " + std::to_string(cfg.maxTimeSeconds) +
                                  "] seconds, got " + std::to_string(t));
    }
}

// Size of every image task in a budget of `spp` samples per pixel; a time budget draws tasks of the
// largest size (so a timed job that ended after n tasks has exactly the bits of an spp job of the
// same sample count).
int64_t taskSize(const JobSpec &spec, int64_t firstSample) {
    return imageTaskSize(spec.budget().has_spp() ? spec.budget().spp() : std::numeric_limits<int64_t>::max(),
                         firstSample);
}

// Task `index` of a Markov-chain job (chain tasks only once it is seeded), as the store and the workers
// see it.
v1::TaskSpec chainJobWork(const ChainJob &job, uint64_t index) {
    v1::TaskSpec work;
    switch (job.phaseOf(index)) {
        case ChainJob::Phase::Seeding:
            work.mutable_seeding()->set_first_pixel(job.seedingTask(index).firstPixel);
            work.mutable_seeding()->set_pixel_count(job.seedingTask(index).pixelCount);
            break;
        case ChainJob::Phase::Direct:
            work.mutable_image()->set_first_sample(job.directTask(index).firstSample);
            work.mutable_image()->set_sample_count(job.directTask(index).sampleCount);
            work.mutable_image()->set_direct(true);
            break;
        case ChainJob::Phase::Chain:
            *work.mutable_chain() = farm::toProto(job.chainTask(index));
            break;
    }
    return work;
}

}  // namespace

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
    v1::TaskSpec work;  // task_index and work
    State state = State::Pending;
    int64_t attempt = 0;             // the latest attempt; only its result is accepted
    std::set<std::string> failedOn;  // workers on which an attempt failed
    int failures = 0;
};

struct Master::JobFilm {
    std::mutex mu;
    std::shared_ptr<Film> film;  // set once before the job is visible; immutable after
    // What the merged results form, released when the job ends: an image job's film, or a Markov-chain
    // job's ChainState.
    std::optional<ImageBlock> block;
    std::unique_ptr<ChainState> chain;
    bool open() const { return block || chain; }
    int64_t merged = 0;        // tasks [0, merged) are in `block`
    int64_t checkpointed = 0;  // tasks [0, checkpointed) are in the checkpoint file
    int64_t spp = 0;           // image jobs: samples per pixel merged
    struct Pending {
        std::string file;
        v1::TaskStats stats;
        v1::TaskSpec work;
    };
    std::map<int64_t, Pending> pending;  // accepted, waiting for their turn
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
};

struct Master::JobRuntime {
    v1::Job record;                  // spec, state, error, times and merged figures; counts are filled in by snapshot()
    std::vector<TaskRuntime> tasks;  // issued tasks, by index
    std::set<int64_t> retry;         // issued tasks waiting for another attempt, lowest first
    int64_t nextFirstSample = 0;
    int64_t total = 0;  // tasks the job will have; 0 while a time budget is open or the seeding runs
    // Markov-chain jobs: tasks [0, chainFirst) seed the chains and render the direct component; chain tasks
    // are issued once `seeded` (the normalizer exists, and is immutable from then on).
    bool chain = false;
    int64_t seedingTasks = 0, chainFirst = 0, seedingSpp = 0;
    bool seeded = false;
    std::map<std::string, int> failuresByWorker;
    std::set<std::string> blocklist;
    double taskSeconds = 0;  // of accepted results that the time budget issues, for its estimate
    int64_t taskCount = 0;
    int64_t failedAttempts = 0, expiredAttempts = 0;
    std::map<int64_t, int64_t> attemptTask;  // every attempt of this job -> its task
    bool filmOpen = false;                   // the film still holds memory or result files to release once the job ends
    JobFilm film;
};

struct Master::WorkerRuntime {
    v1::WorkerInfo info;
    Clock::time_point lastSeen;
    bool draining = false;
    std::set<int64_t> attempts;
    // Completed tasks in their two units: pixel samples (image and seeding tasks), mutations (chains).
    double renderSeconds = 0, mutationSeconds = 0;
    uint64_t samples = 0, mutations = 0;
};

Master::Master(MasterConfig config)
    : cfg_(std::move(config)),
      bundles_((fs::create_directories(cfg_.dataDir), (fs::path(cfg_.dataDir) / "bundles").string()),
               cfg_.maxBundleBytes),
      store_((fs::path(cfg_.dataDir) / "store.sqlite").string()) {
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

// ---------------------------------------------------------------------------------------------------
// Submission and recovery

Master::Loaded Master::load(const JobSpec &spec, v1::Job &record) const {
    if (!bundles_.has(spec.bundle_hash()))
        throw farm::FarmError("job spec: unknown bundle '" + spec.bundle_hash() + "' (upload it first)");
    const v1::BundleManifest manifest = bundles_.manifest(spec.bundle_hash());
    const auto t0 = Clock::now();
    const std::string root = fs::absolute(bundles_.dir(spec.bundle_hash())).string() + "/";
    std::unique_ptr<Scene> scene;
    std::unique_ptr<Integrator> integrator;
    std::vector<SceneWarning> warnings;
    try {
        const std::lock_guard<std::mutex> lock(sceneLoadMu_);
        scene = loadScene(root + manifest.scene_file(), farm::toNameValues(spec.defines()), spec.strict());
        warnings = scene->warnings();
        integrator =
            makeIntegrator(*scene, spec.integrator(), farm::toNameValues(spec.params()), spec.strict(), &warnings);
    } catch (const SceneError &e) {
        throw SceneError(relativeTo(root, e.what()));
    }
    // Recovery loads a job again: its warnings are replaced, not repeated.
    record.clear_warnings();
    for (const SceneWarning &w : warnings) record.add_warnings(relativeTo(root, w.str()));
    const Film &film = scene->sensor().film();
    if (static_cast<int64_t>(film.cropWidth()) * film.cropHeight() > cfg_.maxPixels)
        throw farm::FarmError("job spec: " + std::to_string(film.cropWidth()) + "x" +
                              std::to_string(film.cropHeight()) + " pixels exceed this master's limit of " +
                              std::to_string(cfg_.maxPixels));
    const auto *chain = dynamic_cast<const ChainIntegrator *>(integrator.get());
    if (!chain && !dynamic_cast<const SamplingIntegrator *>(integrator.get()))
        throw farm::FarmError("job spec: integrator '" + integrator->name() +
                              "' renders neither in image tasks nor in chain tasks");
    // A chain integrator refuses budgets it cannot split into tasks (SceneError, for the submitter).
    if (chain && record.spec().budget().has_spp()) chain->chainTaskCount(*scene, record.spec().budget().spp());
    record.set_scene_file(manifest.scene_file());
    record.set_integrator(integrator->name());
    record.set_width(film.cropWidth());
    record.set_height(film.cropHeight());
    record.set_scene_load_seconds(std::chrono::duration<double>(Clock::now() - t0).count());
    if (!record.spec().budget().has_spp() && !record.spec().budget().has_time_seconds())
        record.mutable_spec()->mutable_budget()->set_spp(scene->sensor().sampleCount());
    return {std::move(scene), std::move(integrator)};
}

void Master::openFilm(JobRuntime &j, Loaded loaded) {
    JobFilm &f = j.film;
    f.film = loaded.scene->sensor().filmPtr();
    const auto *chain = dynamic_cast<const ChainIntegrator *>(loaded.integrator.get());
    if (!chain) {
        // An image job needs only the film; the scene's memory goes.
        f.block.emplace(0, 0, f.film->cropWidth(), f.film->cropHeight(), &f.film->filter());
        j.filmOpen = true;
        return;
    }
    const JobSpec &spec = j.record.spec();
    auto state = std::make_unique<ChainState>();
    state->job = std::make_unique<ChainJob>(*loaded.scene, *chain, spec.seed(),
                                            spec.budget().has_spp() ? spec.budget().spp() : 0);
    state->loaded = std::move(loaded);
    const ChainJob &job = *state->job;
    j.chain = true;
    j.seedingTasks = static_cast<int64_t>(job.seedingTaskCount());
    j.chainFirst = static_cast<int64_t>(job.firstChainTask());
    j.seedingSpp = job.seedingConfig().samplesPerPixel;
    v1::ChainStats *stats = j.record.mutable_chain();
    if (stats->phase() == v1::CHAIN_PHASE_UNSPECIFIED) stats->set_phase(v1::CHAIN_PHASE_SEEDING);
    stats->set_seeding_tasks(job.seedingTaskCount());
    stats->set_direct_tasks(job.directTaskCount());
    stats->set_seeding_samples_per_pixel(j.seedingSpp);
    f.chain = std::move(state);
    j.filmOpen = true;
}

v1::Job Master::submit(const JobSpec &spec) {
    checkSpec(spec, cfg_);
    auto j = std::make_unique<JobRuntime>();
    *j->record.mutable_spec() = spec;
    openFilm(*j, load(spec, j->record));
    // A chain job's total is known once its seeding tells whether the image carries any energy.
    if (j->record.spec().budget().has_spp() && !j->chain)
        for (int64_t first = 0; first < j->record.spec().budget().spp(); first += taskSize(j->record.spec(), first))
            ++j->total;
    j->record.mutable_tasks()->set_total(j->total);
    j->record.set_state(v1::JOB_QUEUED);
    j->record.set_created_unix_ms(unixMs());
    store_.createJob(j->record);
    fs::create_directories(fs::path(jobDir(j->record.id())) / "results");

    const std::lock_guard<std::mutex> lock(mu_);
    const int64_t id = j->record.id();
    spdlog::info("job={}: submitted: {} ({}x{}), {}, {}, seed {}, priority {}", id, j->record.scene_file(),
                 j->record.width(), j->record.height(), j->record.integrator(),
                 spec.budget().has_time_seconds() ? std::to_string(spec.budget().time_seconds()) + " s"
                                                  : std::to_string(j->record.spec().budget().spp()) + " spp",
                 spec.seed(), spec.priority());
    JobRuntime &ref = *j;
    jobs_.emplace(id, std::move(j));
    touch();
    workChanged_.notify_all();
    return snapshot(ref);
}

void Master::recover() {
    const auto now = Clock::now();
    for (v1::WorkerInfo &w : store_.loadWorkers()) {
        auto rt = std::make_unique<WorkerRuntime>();
        w.set_state(v1::WORKER_LOST);  // until it shows up again
        w.clear_attempt_ids();
        rt->info = std::move(w);
        rt->lastSeen = now - cfg_.leaseTime;
        workers_.emplace(rt->info.id(), std::move(rt));
    }
    for (const StoredJob &stored : store_.loadJobs()) {
        if (isActive(stored.record.state())) {
            recoverJob(stored);
        } else {
            auto j = std::make_unique<JobRuntime>();
            j->record = stored.record;
            jobs_.emplace(stored.record.id(), std::move(j));
        }
    }
}

void Master::recoverJob(const StoredJob &stored) {
    auto owned = std::make_unique<JobRuntime>();
    JobRuntime &j = *owned;
    j.record = stored.record;
    const int64_t id = j.record.id();
    jobs_.emplace(id, std::move(owned));
    j.total = j.record.tasks().total();
    try {
        v1::Job reloaded = j.record;
        openFilm(j, load(j.record.spec(), reloaded));
        if (j.chain) {
            // The seeding results merged before the restart are merged again from their files, then the
            // checkpoint puts back the direct component and the chains.
            ChainJob &job = *j.film.chain->job;
            for (const StoredResult &r : store_.loadResults(id, std::min(stored.mergedTasks, j.seedingTasks)))
                job.mergeSeeding(std::get<SeedingResult>(
                    decodeOutput(j, chainJobWork(job, static_cast<uint64_t>(r.taskIndex)), farm::readFile(r.file))));
            if (!stored.checkpoint.empty()) {
                v1::ChainCheckpoint cp;
                if (!cp.ParseFromString(farm::readFile(stored.checkpoint)))
                    throw farm::FarmError("corrupt checkpoint " + stored.checkpoint);
                ImageBlock direct = makeFilmBlock(job.scene());
                farm::decodeBlock(cp.direct(), direct);
                job.restore(std::move(direct), cp.direct_samples_per_pixel(),
                            farm::fromProto(cp.chains(), makeFilmBlock(job.scene())));
            }
        } else if (!stored.checkpoint.empty()) {
            farm::decodeBlock(farm::readFile(stored.checkpoint), *j.film.block);
        }
    } catch (const std::exception &e) {
        spdlog::error("job={}: cannot resume after a restart: {}", id, e.what());
        j.film.block.reset();
        j.film.chain.reset();
        setState(j, v1::JOB_FAILED, std::string("cannot resume after a restart: ") + e.what());
        return;
    }
    j.film.merged = j.film.checkpointed = stored.mergedTasks;
    j.film.checkpointFile = stored.checkpoint;
    j.film.spp = j.record.samples_per_pixel();

    for (const StoredTask &t : store_.loadTasks(id)) {
        if (t.index != static_cast<int64_t>(j.tasks.size()))
            throw std::runtime_error("store: job " + std::to_string(id) + " has a gap in its tasks");
        TaskRuntime rt;
        rt.work = t.work;
        rt.work.set_task_index(t.index);
        rt.state = t.state == task_state::kMerged     ? TaskRuntime::State::Merged
                   : t.state == task_state::kAccepted ? TaskRuntime::State::Accepted
                   : t.state == task_state::kLeased   ? TaskRuntime::State::Leased
                                                      : TaskRuntime::State::Pending;
        j.nextFirstSample = rt.work.image().first_sample() + rt.work.image().sample_count();
        j.tasks.push_back(std::move(rt));
    }
    // Leases survive the restart with a fresh deadline: their workers reconnect and carry on.
    const auto deadline = Clock::now() + cfg_.leaseTime;
    for (const StoredAttempt &a : store_.loadAttempts(id)) {
        TaskRuntime &t = j.tasks.at(static_cast<size_t>(a.taskIndex));
        t.attempt = a.id;
        j.attemptTask[a.id] = a.taskIndex;
        if (a.state == attempt_state::kFailed || a.state == attempt_state::kExpired) {
            ++j.failuresByWorker[a.workerId];
            (a.state == attempt_state::kFailed ? j.failedAttempts : j.expiredAttempts)++;
        }
        if (a.state == attempt_state::kFailed) {
            ++t.failures;
            t.failedOn.insert(a.workerId);
        }
        if (a.state == attempt_state::kLeased && t.state == TaskRuntime::State::Leased) {
            leases_[a.id] = {id, a.taskIndex, a.workerId, deadline};
            if (const auto w = workers_.find(a.workerId); w != workers_.end()) w->second->attempts.insert(a.id);
        }
    }
    for (size_t i = 0; i < j.tasks.size(); ++i)
        if (j.tasks[i].state == TaskRuntime::State::Pending ||
            (j.tasks[i].state == TaskRuntime::State::Leased && !leases_.count(j.tasks[i].attempt)))
            j.retry.insert(static_cast<int64_t>(i));
    for (const std::string &w : store_.loadBlocklist(id)) j.blocklist.insert(w);
    for (const StoredResult &r : store_.loadUnmergedResults(id)) {
        const v1::TaskSpec &work = j.tasks.at(static_cast<size_t>(r.taskIndex)).work;
        j.film.pending[r.taskIndex] = {r.file, r.stats, work};
        if (r.taskIndex >= j.chainFirst) {
            j.taskSeconds += r.stats.seconds();
            ++j.taskCount;
        }
    }
    if (j.chain && j.film.chain->job->seeded()) startChains(j);
    spdlog::info("job={}: resumed: {} tasks issued, {} merged in the checkpoint, {} results waiting, {} leases", id,
                 j.tasks.size(), j.film.merged, j.film.pending.size(), leases_.size());
    // No other thread runs yet; the film mutex is taken for the locking discipline of mergeReady.
    const std::lock_guard<std::mutex> lock(j.film.mu);
    mergeReady(j, std::nullopt);
}

// ---------------------------------------------------------------------------------------------------
// Queries

v1::Job Master::snapshot(const JobRuntime &j) const {
    v1::Job job = j.record;
    if (j.tasks.empty() && !isActive(job.state())) return job;  // a finished job's stored figures
    auto *c = job.mutable_tasks();
    c->set_total(j.total);
    c->set_issued(static_cast<int64_t>(j.tasks.size()));
    int64_t leased = 0, accepted = 0;
    for (const TaskRuntime &t : j.tasks) {
        leased += t.state == TaskRuntime::State::Leased;
        accepted += t.state == TaskRuntime::State::Accepted || t.state == TaskRuntime::State::Merged;
    }
    c->set_leased(leased);
    c->set_accepted(accepted);
    c->set_failed_attempts(j.failedAttempts);
    c->set_expired_attempts(j.expiredAttempts);
    job.clear_blocklisted_workers();
    for (const std::string &w : j.blocklist) job.add_blocklisted_workers(w);
    double progress = 0;
    if (job.state() == v1::JOB_DONE) {
        progress = 1;
    } else if (j.total > 0) {
        progress = static_cast<double>(c->merged()) / static_cast<double>(j.total);
    } else if (job.started_unix_ms() > 0 && job.spec().budget().has_time_seconds()) {
        progress = std::min(0.99, (unixMs() - job.started_unix_ms()) / 1000.0 / job.spec().budget().time_seconds());
    }
    job.set_progress(progress);
    if (job.state() == v1::JOB_RUNNING) job.set_render_seconds((unixMs() - job.started_unix_ms()) / 1000.0);
    return job;
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

std::shared_ptr<const Bitmap> Master::preview(int64_t id) {
    JobRuntime *j = nullptr;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        const auto it = jobs_.find(id);
        if (it == jobs_.end()) return nullptr;
        j = it->second.get();
    }
    JobFilm &f = j->film;
    const std::lock_guard<std::mutex> filmLock(f.mu);
    const auto now = Clock::now();
    if (f.open() && f.merged > f.previewMerged && now - f.lastPreview >= std::chrono::milliseconds(250)) {
        f.preview = std::make_shared<const Bitmap>(develop(*j));
        f.previewMerged = f.merged;
        f.lastPreview = now;
    }
    return f.preview;
}

std::optional<Master::ExrImage> Master::image(int64_t id) const {
    JobRuntime *j = nullptr;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        const auto it = jobs_.find(id);
        if (it == jobs_.end()) return std::nullopt;
        j = it->second.get();
    }
    const std::lock_guard<std::mutex> filmLock(j->film.mu);
    ExrImage out;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        out.final = j->record.state() == v1::JOB_DONE;
        out.samplesPerPixel = j->record.samples_per_pixel();
    }
    // A job that ended has its image in a file (final, or what a cancelled or failed job got to);
    // a running one is developed now.
    const fs::path ended = fs::path(jobDir(id)) / "image.exr";
    std::error_code ec;
    if (fs::exists(ended, ec)) {
        out.bytes = farm::readFile(ended.string());
        return out;
    }
    if (!j->film.open() || j->film.merged == 0) return std::nullopt;
    // writeEXR writes files only; the running image goes through a private temporary one.
    const fs::path tmp = fs::path(jobDir(id)) / "running.exr";
    writeEXR(tmp.string(), develop(*j));
    out.bytes = farm::readFile(tmp.string());
    fs::remove(tmp);
    return out;
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

// ---------------------------------------------------------------------------------------------------
// Jobs' lifecycle

void Master::setState(JobRuntime &j, v1::JobState state, const std::string &error) {
    j.record.set_state(state);
    if (!error.empty()) j.record.set_error(error);
    if (!isActive(state)) {
        if (j.record.finished_unix_ms() == 0) j.record.set_finished_unix_ms(unixMs());
        if (j.record.started_unix_ms() > 0)
            j.record.set_render_seconds((j.record.finished_unix_ms() - j.record.started_unix_ms()) / 1000.0);
        for (auto it = leases_.begin(); it != leases_.end();) {
            if (it->second.job != j.record.id()) {
                ++it;
                continue;
            }
            if (const auto w = workers_.find(it->second.worker); w != workers_.end())
                w->second->attempts.erase(it->first);
            it = leases_.erase(it);
        }
        store_.cancelAttempts(j.record.id(), unixMs());
        j.retry.clear();
    }
    // Finished jobs keep their final figures in the stored record.
    store_.saveJob(snapshot(j));
    spdlog::log(state == v1::JOB_FAILED ? spdlog::level::err : spdlog::level::info, "job={}: {}{}", j.record.id(),
                farm::stateName(state), error.empty() ? "" : ": " + error);
    touch();
}

std::optional<v1::Job> Master::cancel(int64_t id) {
    const std::lock_guard<std::mutex> lock(mu_);
    const auto it = jobs_.find(id);
    if (it == jobs_.end()) return std::nullopt;
    JobRuntime &j = *it->second;
    if (isActive(j.record.state())) setState(j, v1::JOB_CANCELLED);  // the reaper then closes its film
    return snapshot(j);
}

// ---------------------------------------------------------------------------------------------------
// Workers and leases

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

std::optional<v1::TaskSpec> Master::lease(const std::string &worker, std::chrono::milliseconds wait) {
    const auto until = Clock::now() + std::min<std::chrono::milliseconds>(wait, std::chrono::seconds(30));
    std::unique_lock<std::mutex> lock(mu_);
    for (;;) {
        const auto it = workers_.find(worker);
        if (it == workers_.end()) throw UnknownWorker("unknown worker '" + worker + "'");
        WorkerRuntime &w = *it->second;
        w.lastSeen = Clock::now();
        w.info.set_last_seen_unix_ms(unixMs());
        if (w.info.state() == v1::WORKER_LOST) w.info.set_state(v1::WORKER_IDLE);
        if (w.draining || stopping_) return std::nullopt;
        if (auto task = pickTask(w)) return task;
        if (workChanged_.wait_until(lock, until) == std::cv_status::timeout) return std::nullopt;
    }
}

std::optional<v1::TaskSpec> Master::pickTask(WorkerRuntime &w) {
    std::vector<JobRuntime *> order;
    for (auto &[id, j] : jobs_)
        if (isActive(j->record.state())) order.push_back(j.get());
    std::stable_sort(order.begin(), order.end(), [](const JobRuntime *a, const JobRuntime *b) {
        return a->record.spec().priority() > b->record.spec().priority();
    });
    const auto &algs = w.info.algorithms();
    for (JobRuntime *jp : order) {
        JobRuntime &j = *jp;
        if (j.blocklist.count(w.info.id())) continue;
        if (!algs.empty() && std::find(algs.begin(), algs.end(), j.record.integrator()) == algs.end()) continue;
        const std::optional<int64_t> index = nextTaskFor(j, w);
        if (!index) continue;
        TaskRuntime &t = j.tasks[static_cast<size_t>(*index)];
        const bool isNew = t.attempt == 0 && t.failures == 0;
        v1::TaskSpec spec = t.work;
        spec.set_job_id(j.record.id());
        *spec.mutable_job() = j.record.spec();
        spec.set_scene_file(j.record.scene_file());
        const int64_t now = unixMs();
        const int64_t attempt = store_.leaseTask(j.record.id(), spec, isNew, w.info.id(), now);
        spec.set_attempt_id(attempt);
        t.state = TaskRuntime::State::Leased;
        t.attempt = attempt;
        j.attemptTask[attempt] = *index;
        leases_[attempt] = {j.record.id(), *index, w.info.id(), Clock::now() + cfg_.leaseTime};
        w.attempts.insert(attempt);
        if (j.record.state() == v1::JOB_QUEUED) {
            j.record.set_state(v1::JOB_RUNNING);
            j.record.set_started_unix_ms(now);
            store_.saveJob(snapshot(j));
        }
        spdlog::info("job={} task={} attempt={} worker={}: leased, {}", j.record.id(), *index, attempt, w.info.id(),
                     farm::describeWork(spec));
        touch();
        return spec;
    }
    return std::nullopt;
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
        t.work = chainJobWork(*j.film.chain->job, static_cast<uint64_t>(index));
    } else {
        t.work.mutable_image()->set_first_sample(j.nextFirstSample);
        t.work.mutable_image()->set_sample_count(taskSize(j.record.spec(), j.nextFirstSample));
        j.nextFirstSample += t.work.image().sample_count();
    }
    t.work.set_task_index(index);
    j.tasks.push_back(std::move(t));
    return index;
}

bool Master::mayIssue(JobRuntime &j) {
    const int64_t issued = static_cast<int64_t>(j.tasks.size());
    // A chain job's seeding and direct tasks are all issued; its chain tasks wait for b̂.
    if (j.chain && (issued < j.chainFirst || !j.seeded)) return issued < j.chainFirst;
    if (j.total > 0) return issued < j.total;
    if (issued == j.chainFirst) return true;  // a time budget runs at least one task (of chains)
    // The clock decides whether another whole task is issued, never when one stops: issue while the
    // expected end of a new task is within the budget.
    const double elapsed = (unixMs() - j.record.started_unix_ms()) / 1000.0;
    const double estimate = j.taskCount > 0 ? j.taskSeconds / static_cast<double>(j.taskCount) : 0.0;
    if (elapsed + estimate <= j.record.spec().budget().time_seconds()) return true;
    j.total = static_cast<int64_t>(j.tasks.size());
    store_.saveJob(snapshot(j));
    spdlog::info("job={}: time budget reached after {:.2f} s: {} tasks issued", j.record.id(), elapsed, j.total);
    touch();
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
        } else {
            lost.push_back(a);
        }
    }
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
    countFailure(j, worker, error);
    touch();
    workChanged_.notify_all();
}

void Master::fail(const std::string &worker, int64_t attempt, const std::string &error) {
    const std::lock_guard<std::mutex> lock(mu_);
    const auto l = leases_.find(attempt);
    if (l == leases_.end() || l->second.worker != worker) return;  // expired or superseded already
    JobRuntime &j = *jobs_.at(l->second.job);
    const int64_t task = l->second.task;
    const std::string message = error.substr(0, 4096);
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
        const TaskRuntime &t = j->tasks[static_cast<size_t>(a->second)];
        if (t.attempt != attempt || t.state == TaskRuntime::State::Accepted || t.state == TaskRuntime::State::Merged)
            return "superseded: task " + std::to_string(a->second) + " was given to another attempt";
        if (!isActive(j->record.state()))
            return "job " + std::to_string(id) + " is " + farm::stateName(j->record.state());
        const auto l = leases_.find(attempt);
        if (l != leases_.end() && l->second.worker != worker) return "attempt belongs to another worker";
        return "";
    }
    return "unknown attempt " + std::to_string(attempt);
}

uint64_t Master::maxPayloadBytes(int64_t attempt) const {
    const std::lock_guard<std::mutex> lock(mu_);
    for (const auto &[id, j] : jobs_) {
        const auto a = j->attemptTask.find(attempt);
        if (a == j->attemptTask.end() || !j->film.film) continue;
        const v1::TaskSpec &work = j->tasks[static_cast<size_t>(a->second)].work;
        if (work.has_seeding()) {
            // Packed path records take at most 38 bytes; a BDPT sample yields one candidate per strategy.
            constexpr uint64_t kRecordBytes = 40, kMaxCandidatesPerSample = 256;
            return work.seeding().pixel_count() * static_cast<uint64_t>(j->seedingSpp) * kMaxCandidatesPerSample *
                       kRecordBytes +
                   (64 << 10);
        }
        // A film block (inside a ChainOutput for chain tasks, beside a few counts).
        const Film &f = *j->film.film;
        const uint64_t b = static_cast<uint64_t>(f.filter().borderSize());
        const uint64_t raw = 7 * sizeof(double) * (f.cropWidth() + 2 * b) * (f.cropHeight() + 2 * b);
        return raw + raw / 128 + (64 << 10);  // zstd's worst case is below raw + raw/256 + a header
    }
    return 0;
}

v1::CompleteReply Master::complete(const std::string &worker, int64_t attempt, const v1::TaskStats &stats,
                                   const std::string &payload) {
    if (const std::string reason = checkAttempt(worker, attempt); !reason.empty())
        return ignoreResult(worker, attempt, reason);

    JobRuntime *j = nullptr;
    int64_t task = 0;
    v1::TaskSpec work;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        for (auto &[id, job] : jobs_)
            if (const auto a = job->attemptTask.find(attempt); a != job->attemptTask.end()) {
                j = job.get();
                task = a->second;
                work = j->tasks[static_cast<size_t>(task)].work;
            }
    }
    const int64_t jobId = j->record.id();
    const auto t0 = Clock::now();
    std::optional<TaskOutput> output;
    try {
        output.emplace(decodeOutput(*j, work, payload));
    } catch (const farm::FarmError &e) {
        fail(worker, attempt, std::string("corrupt result: ") + e.what());
        throw;
    }
    const double decodeSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    const fs::path file =
        fs::path(jobDir(jobId)) / "results" / (std::to_string(task) + "-" + std::to_string(attempt) + ".blk");
    writeFileAtomic(file, payload, false);

    bool accepted = false;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        // The lease may have expired or the job ended while the payload was on its way.
        TaskRuntime &t = j->tasks[static_cast<size_t>(task)];
        if (!isActive(j->record.state()) || t.attempt != attempt || t.state == TaskRuntime::State::Accepted ||
            t.state == TaskRuntime::State::Merged) {
            fs::remove(file);
        } else {
            store_.acceptResult(jobId, task, attempt, file.string(), payload.size(), stats, unixMs());
            t.state = TaskRuntime::State::Accepted;
            accepted = true;
            leases_.erase(attempt);
            j->retry.erase(task);
            if (task >= j->chainFirst) {
                j->taskSeconds += stats.seconds();
                ++j->taskCount;
            }
            if (const auto w = workers_.find(worker); w != workers_.end()) {
                WorkerRuntime &wr = *w->second;
                wr.attempts.erase(attempt);
                wr.info.set_tasks_completed(wr.info.tasks_completed() + 1);
                (work.has_chain() ? wr.mutationSeconds : wr.renderSeconds) += stats.seconds();
                (work.has_chain() ? wr.mutations : wr.samples) += stats.samples();
            }
            counters_.resultBytes += payload.size();
            counters_.mergeSeconds += decodeSeconds;
            spdlog::info("job={} task={} attempt={} worker={}: accepted, {} bytes, {:.3f} s on the worker", jobId, task,
                         attempt, worker, payload.size(), stats.seconds());
            touch();
        }
    }
    if (!accepted) return ignoreResult(worker, attempt, checkAttempt(worker, attempt));
    {
        const std::lock_guard<std::mutex> filmLock(j->film.mu);
        j->film.pending[task] = {file.string(), stats, work};
        mergeReady(*j, std::make_optional(std::make_pair(task, std::move(*output))));
    }
    v1::CompleteReply reply;
    reply.set_accepted(true);
    return reply;
}

v1::CompleteReply Master::ignoreResult(const std::string &worker, int64_t attempt, const std::string &reason) {
    const std::lock_guard<std::mutex> lock(mu_);
    if (reason.rfind("superseded", 0) == 0) {
        store_.ignoreAttempt(attempt, unixMs());
        ++counters_.lateResultsIgnored;
    }
    spdlog::warn("attempt={} worker={}: result ignored: {}", attempt, worker, reason);
    v1::CompleteReply reply;
    reply.set_accepted(false);
    reply.set_reason(reason);
    return reply;
}

// ---------------------------------------------------------------------------------------------------
// Merging, checkpoints, the final image

Bitmap Master::develop(const JobRuntime &j) const {
    if (j.film.chain) return j.film.chain->job->develop();
    return j.film.film->develop(*j.film.block, 1.0 / static_cast<double>(j.film.spp));
}

Master::TaskOutput Master::decodeOutput(const JobRuntime &j, const v1::TaskSpec &work, std::string_view payload) const {
    const Film &film = *j.film.film;
    const auto emptyBlock = [&] { return ImageBlock(0, 0, film.cropWidth(), film.cropHeight(), &film.filter()); };
    if (work.has_seeding())
        return farm::decodeSeedingResult(payload, film,
                                         SeedingTask{work.seeding().first_pixel(), work.seeding().pixel_count()});
    if (work.has_chain()) return farm::decodeChainResult(payload, emptyBlock());
    ImageBlock block = emptyBlock();
    farm::decodeBlock(payload, block);
    return block;
}

void Master::mergeOutput(JobRuntime &j, const v1::TaskSpec &work, TaskOutput output) {
    JobFilm &f = j.film;
    if (!f.chain) {
        f.block->merge(std::get<ImageBlock>(output));
        f.spp += work.image().sample_count();
        return;
    }
    ChainJob &job = *f.chain->job;
    if (work.has_seeding()) {
        job.mergeSeeding(std::move(std::get<SeedingResult>(output)));
    } else if (work.has_chain()) {
        job.mergeChain(std::get<ChainResult>(output));
    } else {
        job.mergeDirect(std::get<ImageBlock>(output), work.image().sample_count());
    }
    f.spp = job.mutationsPerPixel();
}

void Master::startChains(JobRuntime &j) {
    if (j.seeded) return;
    const ChainJob &job = *j.film.chain->job;
    j.seeded = true;
    const uint64_t count = job.chainTaskCount();
    if (j.total == 0 && count != UINT64_MAX) j.total = j.chainFirst + static_cast<int64_t>(count);
    v1::ChainStats *stats = j.record.mutable_chain();
    stats->set_phase(v1::CHAIN_PHASE_CHAINS);
    stats->set_luminance(job.normalizer().luminance());
    stats->set_candidates(job.normalizer().candidates().size());
    spdlog::info("job={}: seeding merged: b = {:.6g} from {} candidates; {} chain tasks", j.record.id(),
                 job.normalizer().luminance(), job.normalizer().candidates().size(),
                 count == UINT64_MAX ? std::string("time budget decides the") : std::to_string(count));
    workChanged_.notify_all();
}

void Master::mergeReady(JobRuntime &j, std::optional<std::pair<int64_t, TaskOutput>> fresh) {
    JobFilm &f = j.film;
    if (!f.open()) return;
    const int64_t before = f.merged;
    // TaskStats.samples by the task's unit: pixel samples of image tasks (the direct component's
    // apart), BDPT samples of seeding tasks, mutations of chain tasks.
    uint64_t samples = 0, seedingSamples = 0, directSamples = 0, mutations = 0, rays = 0;
    double seconds = 0, loadSeconds = 0;
    for (auto it = f.pending.find(f.merged); it != f.pending.end(); it = f.pending.find(f.merged)) {
        const auto t0 = Clock::now();
        const v1::TaskSpec &work = it->second.work;
        try {
            mergeOutput(j, work,
                        fresh && fresh->first == f.merged ? std::move(fresh->second)
                                                          : decodeOutput(j, work, farm::readFile(it->second.file)));
        } catch (const std::exception &e) {
            // The master's own file is unreadable: the disk failed, and the job cannot be exact.
            const std::lock_guard<std::mutex> lock(mu_);
            setState(j, v1::JOB_FAILED, "stored result of task " + std::to_string(f.merged) + ": " + e.what());
            return;
        }
        seconds += std::chrono::duration<double>(Clock::now() - t0).count();
        (work.has_seeding()                          ? seedingSamples
         : work.has_chain()                          ? mutations
         : work.has_image() && work.image().direct() ? directSamples
                                                     : samples) += it->second.stats.samples();
        rays += it->second.stats.rays();
        loadSeconds += it->second.stats.scene_load_seconds();
        if (!work.has_seeding()) f.mergedSinceCheckpoint.push_back(it->second.file);
        f.pending.erase(it);
        ++f.merged;
    }
    if (f.merged == before) return;
    const auto now = Clock::now();
    const bool complete = j.total > 0 && f.merged == j.total;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        for (int64_t t = before; t < f.merged; ++t) j.tasks[static_cast<size_t>(t)].state = TaskRuntime::State::Merged;
        j.record.mutable_tasks()->set_merged(f.merged);
        const uint64_t pixelSamples = samples + seedingSamples + directSamples;
        j.record.set_samples_per_pixel(f.spp);
        j.record.set_samples(j.record.samples() + pixelSamples);
        j.record.set_rays(j.record.rays() + rays);
        j.record.set_worker_scene_load_seconds(j.record.worker_scene_load_seconds() + loadSeconds);
        if (f.chain) {
            v1::ChainStats *stats = j.record.mutable_chain();
            const ChainImage &chains = f.chain->job->chains();
            stats->set_mutations(chains.mutations);
            stats->set_mutations_per_pixel(f.chain->job->mutationsPerPixel());
            stats->set_seeding_samples(stats->seeding_samples() + seedingSamples);
            stats->set_direct_samples(stats->direct_samples() + directSamples);
            stats->set_direct_samples_per_pixel(f.chain->job->directSamplesPerPixel());
            farm::toProto(chains.counts, *stats->mutable_mutation_counts());
            farm::toProto(chains.counters, *stats->mutable_counters());
            if (f.chain->job->seeded()) startChains(j);
        }
        counters_.resultsMerged += f.merged - before;
        counters_.mergeSeconds += seconds;
        counters_.samplesMerged += pixelSamples;
        counters_.mutationsMerged += mutations;
        const int64_t second = std::chrono::duration_cast<std::chrono::seconds>(now.time_since_epoch()).count();
        if (recentSamples_.empty() || recentSamples_.back().first != second) recentSamples_.emplace_back(second, 0);
        recentSamples_.back().second += pixelSamples;
        while (recentSamples_.front().first < second - 59) recentSamples_.pop_front();
        touch();
    }
    // Checkpoints only shorten the replay after a restart (results stay on disk until then), so a large
    // film is checkpointed less often: at most 5% of the master's time goes into them.
    const auto checkpointDue = std::max<Clock::duration>(cfg_.checkpointInterval, 20 * f.checkpointCost);
    if (complete) {
        finishIfComplete(j);
    } else if (now - f.lastCheckpoint >= checkpointDue) {
        checkpoint(j);
    }
}

void Master::checkpoint(JobRuntime &j) {
    JobFilm &f = j.film;
    if (f.merged == f.checkpointed) return;
    const auto start = Clock::now();
    const fs::path file = fs::path(jobDir(j.record.id())) / ("checkpoint-" + std::to_string(f.merged) + ".blk");
    if (f.chain) {
        const ChainJob &job = *f.chain->job;
        v1::ChainCheckpoint cp;
        cp.set_direct(farm::encodeBlock(job.direct()));
        cp.set_direct_samples_per_pixel(job.directSamplesPerPixel());
        *cp.mutable_chains() = farm::toProto(job.chains());
        writeFileAtomic(file, cp.SerializeAsString(), true);
    } else {
        writeFileAtomic(file, farm::encodeBlock(*f.block), true);
    }
    v1::Job record;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        record = snapshot(j);
    }
    store_.commitCheckpoint(record, f.checkpointed, f.merged, file.string(), unixMs());
    // Only now are the old checkpoint and the merged results redundant.
    std::error_code ec;
    if (!f.checkpointFile.empty() && f.checkpointFile != file.string()) fs::remove(f.checkpointFile, ec);
    for (const std::string &r : f.mergedSinceCheckpoint) fs::remove(r, ec);
    f.mergedSinceCheckpoint.clear();
    spdlog::debug("job={}: checkpoint of {} tasks", j.record.id(), f.merged);
    f.checkpointed = f.merged;
    f.checkpointFile = file.string();
    f.lastCheckpoint = Clock::now();
    f.checkpointCost = f.lastCheckpoint - start;
}

void Master::finishIfComplete(JobRuntime &j) {
    JobFilm &f = j.film;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        if (j.record.state() != v1::JOB_RUNNING || j.total == 0 || f.merged < j.total || !f.open()) return;
    }
    // The job's true time ends with its last merge, before the I/O of finishing it.
    const int64_t endMs = unixMs();
    const double seconds = (endMs - j.record.started_unix_ms()) / 1000.0;
    checkpoint(j);
    Bitmap image = develop(j);
    const JobSpec &spec = j.record.spec();
    image.metadata["pathfarm.integrator"] = j.record.integrator();
    image.metadata["pathfarm.spp"] = std::to_string(f.spp);
    image.metadata["pathfarm.seed"] = std::to_string(spec.seed());
    image.metadata["pathfarm.renderSeconds"] = std::to_string(seconds);
    image.metadata["pathfarm.sceneLoadSeconds"] = std::to_string(j.record.scene_load_seconds());
    image.metadata["pathfarm.workerSceneLoadSeconds"] = std::to_string(j.record.worker_scene_load_seconds());
    image.metadata["pathfarm.scene"] = j.record.scene_file();
    image.metadata["pathfarm.job"] = std::to_string(j.record.id());
    image.metadata["pathfarm.tasks"] = std::to_string(f.merged);
    if (spec.budget().has_time_seconds())
        image.metadata["pathfarm.timeBudget"] = std::to_string(spec.budget().time_seconds());
    writeEXR((fs::path(jobDir(j.record.id())) / "image.exr").string(), image);
    f.preview = std::make_shared<const Bitmap>(std::move(image));
    f.previewMerged = f.merged;
    const std::lock_guard<std::mutex> lock(mu_);
    j.record.set_finished_unix_ms(endMs);
    setState(j, v1::JOB_DONE);
    spdlog::info("job={}: {} tasks, {} spp in {:.2f} s", j.record.id(), f.merged, f.spp, j.record.render_seconds());
}

void Master::closeFilm(JobRuntime &j) {
    JobFilm &f = j.film;
    if (!f.open()) return;
    // What a cancelled or failed job got to stays fetchable; a finished job has its final image already.
    const fs::path image = fs::path(jobDir(j.record.id())) / "image.exr";
    std::error_code ec;
    if (f.merged > 0 && !fs::exists(image, ec)) {
        f.preview = std::make_shared<const Bitmap>(develop(j));
        f.previewMerged = f.merged;
        writeEXR(image.string(), *f.preview);
    }
    f.block.reset();
    f.chain.reset();
    f.pending.clear();
    fs::remove_all(fs::path(jobDir(j.record.id())) / "results", ec);
}

// ---------------------------------------------------------------------------------------------------
// Expiry of leases, lost workers, closing time budgets

void Master::reaperLoop() {
    const auto period = std::clamp<std::chrono::milliseconds>(cfg_.leaseTime / 10, std::chrono::milliseconds(20),
                                                              std::chrono::milliseconds(500));
    std::unique_lock<std::mutex> lock(mu_);
    while (!stopping_) {
        workChanged_.wait_for(lock, period);
        if (stopping_) break;
        const auto now = Clock::now();
        for (auto it = leases_.begin(); it != leases_.end();) {
            const auto [attempt, lease] = *it++;
            if (lease.deadline > now) continue;
            JobRuntime &j = *jobs_.at(lease.job);
            spdlog::warn("job={} task={} attempt={} worker={}: lease expired", lease.job, lease.task, attempt,
                         lease.worker);
            ++j.expiredAttempts;
            ++counters_.attemptsExpired;
            requeue(j, lease.task, lease.worker, attempt_state::kExpired, "lease expired (no heartbeat)", attempt);
        }
        for (auto &[id, w] : workers_)
            if (w->info.state() != v1::WORKER_LOST && now - w->lastSeen > cfg_.leaseTime) {
                w->info.set_state(v1::WORKER_LOST);
                store_.saveWorker(w->info);
                spdlog::warn("worker={}: lost (no contact for {} ms)", id, cfg_.leaseTime.count());
                touch();
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
