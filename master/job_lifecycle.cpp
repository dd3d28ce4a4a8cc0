// Master: a job's lifecycle. Submission checks the spec and loads the scene (so that the submitter
// learns of bad scenes); recovery rebuilds every unfinished job from the store after a restart, down to
// its leases and the results that wait for their merge; setState moves a job between states and ends
// what an ended job holds in the scheduler. Films are opened here and merged in merger.cpp.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "farm/block_codec.h"
#include "farm/convert.h"
#include "farm/error.h"
#include "farm/job_setup.h"
#include "film_files.h"
#include "job_spec_check.h"
#include "render/image_task.h"
#include "runtime.h"

namespace pf::master {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

// Messages name files as the submitter knows them, relative to the scene's directory.
std::string relativeTo(const std::string &root, std::string msg) {
    for (size_t at; (at = msg.find(root)) != std::string::npos;) msg.erase(at, root.size());
    return msg;
}

}  // namespace

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
    if (const auto *chain = dynamic_cast<const ChainIntegrator *>(loaded.integrator.get())) {
        openChainFilm(j, std::move(loaded), *chain);
    } else {
        // An image job needs only the film; the scene's memory goes.
        f.block.emplace(0, 0, f.film->cropWidth(), f.film->cropHeight(), &f.film->filter());
    }
    j.filmOpen = true;
}

v1::Job Master::submit(const JobSpec &spec) {
    checkJobSpec(spec, cfg_);
    auto j = std::make_unique<JobRuntime>();
    *j->record.mutable_spec() = spec;
    openFilm(*j, load(spec, j->record));
    // A chain job's total is known once its seeding tells whether the image carries any energy.
    if (j->record.spec().budget().has_spp() && !j->chain)
        for (int64_t first = 0; first < j->record.spec().budget().spp(); first += taskSize(j->record, first))
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
    StoredJob film = stored;  // what the film resumes from
    try {
        v1::Job reloaded = j.record;
        openFilm(j, load(j.record.spec(), reloaded));
        try {
            restoreFilm(j, film);
        } catch (const farm::FarmError &e) {
            // The checkpoint (or a chain job's seeding) is unreadable or damaged: every task merged into it
            // is rendered again (tasks are reproducible), into a fresh film.
            spdlog::warn("job={}: its film cannot be restored ({}): rendering its {} merged tasks again", id, e.what(),
                         film.mergedTasks);
            std::error_code ec;
            for (const std::string &file : store_.rewindJob(id)) fs::remove(file, ec);
            if (!film.checkpoint.empty()) fs::remove(film.checkpoint, ec);
            film.mergedTasks = 0;
            film.checkpoint.clear();
            for (auto *r : {&j.record, &reloaded}) {
                r->mutable_tasks()->set_merged(0);
                r->set_samples_per_pixel(0);
                r->set_samples(0);
                r->set_rays(0);
                r->clear_chain();
            }
            openFilm(j, load(j.record.spec(), reloaded));
        }
    } catch (const std::exception &e) {
        // What cannot be rebuilt: the bundle is gone, the scene no longer loads, the store fails.
        spdlog::error("job={}: cannot resume after a restart: {}", id, e.what());
        j.film.block.reset();
        j.film.chain.reset();
        setState(j, v1::JOB_FAILED, std::string("cannot resume after a restart: ") + e.what());
        return;
    }
    j.film.merged = j.film.checkpointed = film.mergedTasks;
    j.film.checkpointFile = film.checkpoint;
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
        // A partial last task that the checkpoint holds (the merges after it are replayed and set it again).
        if (rt.work.has_image() && rt.work.image().tiles() > 0 && t.index < j.film.merged)
            j.film.partialPixels = tilePixels(*j.film.film, rt.work.image().tiles());
        j.tasks.push_back(std::move(rt));
    }
    // Leases survive the restart with a fresh deadline: their workers reconnect and carry on.
    const auto deadline = Clock::now() + cfg_.leaseTime;
    for (const StoredAttempt &a : store_.loadAttempts(id)) {
        TaskRuntime &t = j.tasks.at(static_cast<size_t>(a.taskIndex));
        t.attempt = a.id;
        j.attemptTask[a.id] = a.taskIndex;
        j.attemptWorker[a.id] = a.workerId;
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
    // The later tasks of a batched result share its file: they join their first task's entry (a chain batch's
    // row may pass direct tasks, whose results come between).
    std::map<std::string, int64_t> batchOfFile;
    for (const StoredResult &r : store_.loadUnmergedResults(id)) {
        const v1::TaskSpec &work = j.tasks.at(static_cast<size_t>(r.taskIndex)).work;
        if (const auto b = batchOfFile.find(r.file); b != batchOfFile.end()) {
            JobFilm::Pending &batch = j.film.pending.at(b->second);
            if (batchRow(j, batch.tasks.back(), 2).back() == r.taskIndex) {
                if (work.has_image()) {
                    v1::ImageTask &image = *batch.work.mutable_image();
                    image.set_sample_count(image.sample_count() + work.image().sample_count());
                }
                batch.tasks.push_back(r.taskIndex);
                j.countTime(work, 1, v1::TaskStats());  // the batch's time came with its first task
                continue;
            }
        }
        j.film.pending[r.taskIndex] = {r.file, r.stats, work, std::nullopt, 0, {r.taskIndex}};
        batchOfFile[r.file] = r.taskIndex;
        if (r.taskIndex >= j.chainFirst) j.countTime(work, 1, r.stats);
    }
    if (j.chain && j.film.chain->job->seeded()) startChains(j);
    spdlog::info("job={}: resumed: {} tasks issued, {} merged in the checkpoint, {} results waiting, {} leases", id,
                 j.tasks.size(), j.film.merged, j.film.pending.size(), leases_.size());
    // No other thread runs yet; the film mutex is taken for the locking discipline of mergeReady.
    const std::lock_guard<std::mutex> lock(j.film.mu);
    mergeReady(j, std::nullopt);
}

void Master::restoreFilm(JobRuntime &j, const StoredJob &stored) {
    if (j.chain) {
        restoreChainFilm(j, stored);
    } else if (!stored.checkpoint.empty()) {
        farm::decodeBlock(readFilmFile(stored.checkpoint), *j.film.block);
    }
}

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
        // The clock's share of the budget, but never ahead of the work merged: a job whose tasks have not
        // come back shows what it has, not 99%.
        const double clock = (unixMs() - job.started_unix_ms()) / 1000.0 / job.spec().budget().time_seconds();
        const double work =
            j.tasks.empty() ? 0.0 : static_cast<double>(c->merged()) / static_cast<double>(j.tasks.size());
        progress = std::min({0.99, clock, work});
    }
    job.set_progress(progress);
    if (job.state() == v1::JOB_RUNNING) job.set_render_seconds((unixMs() - job.started_unix_ms()) / 1000.0);
    return job;
}

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

}  // namespace pf::master
