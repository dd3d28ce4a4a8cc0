// Master: a result's way to the film, top to bottom. complete() accepts a result for the attempt that
// holds its task's lease, decodes it (decodeOutput) and stores the payload in a file; mergeReady then
// merges, in task order, every accepted result that is next (mergeOutput), so that the film has exactly
// the bits of a local render; checkpoints let a restarted master resume from the merged film instead
// of replaying every result; finishIfComplete writes the final image, closeFilm releases what an ended
// job holds. preview() and image() develop the film on request.
// Locking: a result is decoded and written with no lock held; the merge holds the job's film mutex and
// takes mu_ only for the short updates of the job's record and the counters (film mutex before mu_).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>

#include "core/error.h"
#include "core/math.h"
#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/error.h"
#include "farm/rpc.h"
#include "film_files.h"
#include "render/image_task.h"
#include "runtime.h"

namespace pf::master {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

uint64_t Master::maxPayloadBytes(int64_t attempt) const {
    const std::lock_guard<std::mutex> lock(mu_);
    for (const auto &[id, j] : jobs_) {
        const auto a = j->attemptTask.find(attempt);
        if (a == j->attemptTask.end() || !j->film.film) continue;
        const v1::TaskSpec &work = j->tasks[static_cast<size_t>(a->second)].work;
        if (work.has_seeding()) return maxSeedingPayloadBytes(*j, work);
        // A film block (inside a ChainOutput for chain tasks, beside a few counts).
        const Film &f = *j->film.film;
        const uint64_t b = static_cast<uint64_t>(f.filter().borderSize());
        const uint64_t raw = 7 * sizeof(double) * (f.cropWidth() + 2 * b) * (f.cropHeight() + 2 * b);
        return raw + raw / 128 + (64 << 10);  // zstd's worst case is below raw + raw/256 + a header
    }
    return 0;
}

v1::CompleteReply Master::complete(const std::string &worker, const std::vector<int64_t> &attempts,
                                   const v1::TaskStats &stats, const std::string &payload) {
    const BatchGovernor::Meter meter(batchGovernor_);
    for (const int64_t a : attempts)
        if (const std::string reason = checkAttempt(worker, a); !reason.empty()) return ignoreResult(worker, a, reason);
    const int64_t attempt = attempts.front();
    const auto count = static_cast<int64_t>(attempts.size());

    JobRuntime *j = nullptr;
    int64_t task = 0;
    v1::TaskSpec work;
    std::vector<int64_t> row;  // the result's tasks
    {
        const std::lock_guard<std::mutex> lock(mu_);
        for (auto &[id, job] : jobs_)
            if (const auto a = job->attemptTask.find(attempt); a != job->attemptTask.end()) {
                j = job.get();
                task = a->second;
                work = j->tasks[static_cast<size_t>(task)].work;
            }
        // A batch is merged as one task of its kind (an image task of all its samples, or a chain task's
        // result that counts as all of them): its tasks must be the batchable ones of a row (batchRow).
        row = batchRow(*j, task, static_cast<size_t>(count));
        for (int64_t i = 0; count > 1 && i < count; ++i) {
            const auto a = j->attemptTask.find(attempts[static_cast<size_t>(i)]);
            const size_t at = static_cast<size_t>(i);
            if (a == j->attemptTask.end() || at >= row.size() || a->second != row[at] || !batchable(*j, a->second))
                throw farm::FarmError("CompleteTask: batched attempt " + std::to_string(attempts[at]) + " is not " +
                                      (j->chain ? "chain" : "image") + " task " +
                                      (at < row.size() ? std::to_string(row[at]) : "beyond the last issued") +
                                      " of job " + std::to_string(j->record.id()) +
                                      " (a batch holds the tasks after attempt " + std::to_string(attempt) +
                                      "'s in order)");
            if (i > 0 && work.has_image()) {
                const auto &next = j->tasks[static_cast<size_t>(a->second)].work.image();
                work.mutable_image()->set_sample_count(work.image().sample_count() + next.sample_count());
            }
        }
    }
    const int64_t jobId = j->record.id();
    const auto t0 = Clock::now();
    std::optional<TaskOutput> output;
    try {
        output.emplace(decodeOutput(*j, work, payload));
    } catch (const farm::FarmError &e) {
        const std::string why = std::string("corrupt result: ") + e.what();
        for (const int64_t a : attempts) fail(worker, a, why);
        throw farm::FarmError(why);
    }
    const double decodeSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    const fs::path file =
        fs::path(jobDir(jobId)) / "results" / (std::to_string(task) + "-" + std::to_string(attempt) + ".blk");
    // A full disk throws StorageError: the worker keeps its lease and retries the upload.
    writeFilmFile(file.string(), payload, false);

    bool accepted = true;
    double transferSeconds = -1;
    {
        const std::lock_guard<std::mutex> lock(mu_);
        // The leases may have expired or the job ended while the payload was on its way.
        for (int64_t i = 0; i < count; ++i) {
            const TaskRuntime &t = j->tasks[static_cast<size_t>(row[static_cast<size_t>(i)])];
            accepted &= isActive(j->record.state()) && t.attempt == attempts[static_cast<size_t>(i)] &&
                        t.state != TaskRuntime::State::Accepted && t.state != TaskRuntime::State::Merged;
        }
        if (!accepted) {
            fs::remove(file);
        } else {
            try {
                store_.acceptResult(jobId, row, attempts, file.string(), payload.size(), stats, unixMs());
            } catch (const StorageError &) {
                std::error_code ec;
                fs::remove(file, ec);
                throw;
            }
            for (int64_t i = 0; i < count; ++i) {
                j->tasks[static_cast<size_t>(row[static_cast<size_t>(i)])].state = TaskRuntime::State::Accepted;
                leases_.erase(attempts[static_cast<size_t>(i)]);
                j->retry.erase(row[static_cast<size_t>(i)]);
            }
            if (task >= j->chainFirst) j->countTime(work, count, stats);
            const auto w = workers_.find(worker);
            if (const Clock::time_point leased = j->tasks[static_cast<size_t>(task)].leased;
                leased != Clock::time_point{}) {
                const int threads = w != workers_.end() ? w->second->info.threads() : 1;
                transferSeconds =
                    std::max(0.0, std::chrono::duration<double>(Clock::now() - leased).count() -
                                      renderWallSeconds(work, count, threads, stats) - stats.scene_load_seconds());
            }
            if (w != workers_.end()) {
                WorkerRuntime &wr = *w->second;
                for (const int64_t a : attempts) {
                    wr.attempts.erase(a);
                    wr.delivered.insert(a);
                }
                wr.info.set_tasks_completed(wr.info.tasks_completed() + count);
                (work.has_chain() ? wr.mutationSeconds : wr.renderSeconds) += stats.seconds();
                (work.has_chain() ? wr.mutations : wr.samples) += stats.samples();
            }
            counters_.resultBytes += payload.size();
            counters_.mergeSeconds += decodeSeconds;
            spdlog::info("job={} task={} attempt={} worker={}: accepted{}, {} bytes, {:.3f} s on the worker", jobId,
                         task, attempt, worker, count > 1 ? " with the next " + std::to_string(count - 1) : "",
                         payload.size(), stats.seconds());
            touch();
        }
    }
    if (!accepted) {
        for (const int64_t a : attempts)
            if (std::string reason = checkAttempt(worker, a); !reason.empty()) return ignoreResult(worker, a, reason);
        return ignoreResult(worker, attempt, checkAttempt(worker, attempt));
    }
    {
        const std::lock_guard<std::mutex> filmLock(j->film.mu);
        JobFilm &f = j->film;
        JobFilm::Pending &p = f.pending[task] = {file.string(), stats, work, std::nullopt, 0, row, transferSeconds};
        if (task == f.merged) {
            mergeReady(*j, std::make_optional(std::make_pair(task, std::move(*output))));
        } else if (const size_t bytes = heldBytes(*output); bytes > 0 && f.heldBytes + bytes <= JobFilm::kHeldBytes) {
            p.output = std::move(*output);
            p.bytes = bytes;
            f.heldBytes += bytes;
        }
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

Master::TaskOutput Master::decodeOutput(const JobRuntime &j, const v1::TaskSpec &work, std::string_view payload) const {
    const Film &film = *j.film.film;
    const auto emptyBlock = [&](BlockStorage storage) {
        return ImageBlock(0, 0, film.cropWidth(), film.cropHeight(), &film.filter(), storage);
    };
    if (work.has_seeding()) return farm::decodeSeedingResult(payload, film, farm::fromProto(work.seeding()));
    // A chain task's film comes as tiles (render/chain.h) and is merged as such, never made dense.
    if (work.has_chain()) return farm::decodeChainResult(payload, emptyBlock(BlockStorage::Tiles));
    std::optional<ImageBlock> block;
    {
        const std::lock_guard<std::mutex> lock(j.film.spareMu);
        if (!j.film.spareBlocks.empty()) {
            block.emplace(std::move(j.film.spareBlocks.back()));
            j.film.spareBlocks.pop_back();
        }
    }
    if (!block) block.emplace(emptyBlock(BlockStorage::Dense));
    std::vector<unsigned char> scratch;
    {
        const std::lock_guard<std::mutex> lock(scratchMu_);
        if (!scratch_.empty()) {
            scratch = std::move(scratch_.back());
            scratch_.pop_back();
        }
    }
    farm::decodeBlock(payload, *block, scratch);
    const std::lock_guard<std::mutex> lock(scratchMu_);
    if (scratch_.size() < kSpareScratch) scratch_.push_back(std::move(scratch));
    return std::move(*block);
}

size_t Master::heldBytes(const TaskOutput &output) {
    // Image and chain results are film blocks; seeding results are merged first and never wait long.
    const ImageBlock *block = std::holds_alternative<ImageBlock>(output)    ? &std::get<ImageBlock>(output)
                              : std::holds_alternative<ChainResult>(output) ? &std::get<ChainResult>(output).film
                                                                            : nullptr;
    return block ? sizeof(double) * block->storedValues() : 0;
}

void Master::mergeReady(JobRuntime &j, std::optional<std::pair<int64_t, TaskOutput>> fresh) {
    JobFilm &f = j.film;
    if (!f.open()) return;
    const int64_t before = f.merged;
    // TaskStats.samples by the task's unit: pixel samples of image tasks (the direct component's
    // apart), BDPT samples of seeding tasks, mutations of chain tasks.
    uint64_t samples = 0, seedingSamples = 0, directSamples = 0, mutations = 0, rays = 0;
    double seconds = 0, loadSeconds = 0;
    // Each timed task's transfer and merge (JobRuntime::overheadSeconds).
    double overheadSeconds = 0;
    int64_t overheadCount = 0;
    // Burst tasks sample their own seeds (render/burst.h): those BDPT samples count as seeding.
    const uint64_t burstSeedsBefore = f.chain ? f.chain->job->chains().seedSamples : 0;
    for (auto it = f.pending.find(f.merged); it != f.pending.end(); it = f.pending.find(f.merged)) {
        const auto t0 = Clock::now();
        const v1::TaskSpec &work = it->second.work;
        std::optional<TaskOutput> output;
        if (fresh && fresh->first == f.merged) {
            output.emplace(std::move(fresh->second));
        } else if (it->second.output) {
            output = std::move(it->second.output);
            f.heldBytes -= it->second.bytes;
        } else {
            try {
                output.emplace(decodeOutput(j, work, readFilmFile(it->second.file)));
            } catch (const farm::FarmError &e) {
                // The master's own file is unreadable, truncated or damaged; the task is reproducible.
                spdlog::warn("job={} task={}: stored result lost ({}): rendering the task again", j.record.id(),
                             f.merged, e.what());
                discardResult(j, it->second.tasks, it->second.file);
                f.pending.erase(it);
                continue;
            }
        }
        mergeOutput(j, work, std::move(*output), static_cast<int64_t>(it->second.tasks.size()));
        const double mergeSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
        seconds += mergeSeconds;
        if (f.merged >= j.chainFirst && it->second.transferSeconds >= 0) {
            overheadSeconds += it->second.transferSeconds + mergeSeconds;
            ++overheadCount;
        }
        (work.has_seeding()                          ? seedingSamples
         : work.has_chain()                          ? mutations
         : work.has_image() && work.image().direct() ? directSamples
                                                     : samples) += it->second.stats.samples();
        rays += it->second.stats.rays();
        loadSeconds += it->second.stats.scene_load_seconds();
        if (!work.has_seeding()) f.mergedSinceCheckpoint.push_back(it->second.file);
        f.mergedAhead.insert(it->second.tasks.begin(), it->second.tasks.end());
        for (auto next = f.mergedAhead.begin(); next != f.mergedAhead.end() && *next == f.merged;
             next = f.mergedAhead.erase(next))
            ++f.merged;
        f.pending.erase(it);
    }
    if (f.merged == before) return;
    if (f.chain) seedingSamples += f.chain->job->chains().seedSamples - burstSeedsBefore;
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
        if (f.chain) recordChainMerge(j, seedingSamples, directSamples);
        j.overheadSeconds += overheadSeconds;
        j.overheadCount += overheadCount;
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
        try {
            checkpoint(j);
        } catch (const StorageError &e) {
            // The results stay on disk until a later checkpoint succeeds.
            storageFault(j, "checkpoint", e);
            f.lastCheckpoint = now;
        }
    }
}

void Master::discardResult(JobRuntime &j, const std::vector<int64_t> &tasks, const std::string &file) {
    const std::lock_guard<std::mutex> lock(mu_);
    std::error_code ec;
    fs::remove(file, ec);
    for (const int64_t t : tasks) {
        store_.discardResult(j.record.id(), t);
        j.tasks[static_cast<size_t>(t)].state = TaskRuntime::State::Pending;
        j.retry.insert(t);
    }
    ++counters_.resultsLost;
    touch();
    workChanged_.notify_all();
}

void Master::storageFault(JobRuntime &j, const char *what, const std::exception &e) {
    // Logged once per distinct fault: the reaper retries a job's final image every period.
    if (j.film.storageFault == e.what()) return;
    j.film.storageFault = e.what();
    spdlog::error("job={}: cannot write its {}: {} (retrying until the data directory has room again)", j.record.id(),
                  what, e.what());
}

void Master::mergeOutput(JobRuntime &j, const v1::TaskSpec &work, TaskOutput output, int64_t tasks) {
    JobFilm &f = j.film;
    if (f.chain) {
        mergeChainOutput(f, work, std::move(output), tasks);
        return;
    }
    ImageBlock &block = std::get<ImageBlock>(output);
    if (const int64_t tiles = work.image().tiles(); tiles > 0) {
        // A time budget's partial last task (scheduler.cpp): where it covers a pixel's whole filter footprint.
        f.partialPixels = tilePixels(*f.film, tiles);
        mergeCoveredPixels(*f.block, std::move(block), *f.film, tiles);
        return;
    }
    f.block->merge(block);
    f.spp += work.image().sample_count();
    const std::lock_guard<std::mutex> lock(f.spareMu);
    if (f.spareBlocks.size() < JobFilm::kSpareBlocks) f.spareBlocks.push_back(std::move(block));
}

void Master::checkpoint(JobRuntime &j) {
    JobFilm &f = j.film;
    // A film that holds tasks after `merged` waits for the task between (JobFilm::mergedAhead): a checkpoint
    // records tasks [0, merged) only, and a restart would merge the others a second time.
    if (f.merged == f.checkpointed || !f.mergedAhead.empty()) return;
    const auto start = Clock::now();
    const fs::path file = fs::path(jobDir(j.record.id())) / ("checkpoint-" + std::to_string(f.merged) + ".blk");
    writeFilmFile(file.string(), f.chain ? chainCheckpoint(*f.chain->job) : farm::encodeBlock(*f.block), true);
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
    // The job is done once its last checkpoint (which records every merge in the store) and its image are
    // written; on a full disk it stays complete but running, and the reaper tries again.
    try {
        checkpoint(j);
        writeFinalImage(j, seconds);
    } catch (const StorageError &e) {
        storageFault(j, "checkpoint", e);
        return;
    } catch (const SceneError &e) {  // writeEXR's errors
        storageFault(j, "final image", e);
        return;
    }
    const std::lock_guard<std::mutex> lock(mu_);
    j.record.set_finished_unix_ms(endMs);
    setState(j, v1::JOB_DONE);
    spdlog::info("job={}: {} tasks, {} spp in {:.2f} s", j.record.id(), f.merged, f.spp, j.record.render_seconds());
}

void Master::writeFinalImage(JobRuntime &j, double seconds) {
    JobFilm &f = j.film;
    Bitmap image = develop(j);
    const JobSpec &spec = j.record.spec();
    image.metadata["pathfarm.integrator"] = j.record.integrator();
    image.metadata["pathfarm.spp"] = std::to_string(f.spp);
    if (f.partialPixels > 0) image.metadata["pathfarm.partialPassPixels"] = std::to_string(f.partialPixels);
    image.metadata["pathfarm.seed"] = std::to_string(spec.seed());
    image.metadata["pathfarm.renderSeconds"] = std::to_string(seconds);
    image.metadata["pathfarm.sceneLoadSeconds"] = std::to_string(j.record.scene_load_seconds());
    image.metadata["pathfarm.workerSceneLoadSeconds"] = std::to_string(j.record.worker_scene_load_seconds());
    image.metadata["pathfarm.scene"] = j.record.scene_file();
    image.metadata["pathfarm.job"] = std::to_string(j.record.id());
    image.metadata["pathfarm.tasks"] = std::to_string(f.merged);
    if (j.record.chain().lambda() > 0) image.metadata["pathfarm.lambda"] = std::to_string(j.record.chain().lambda());
    if (j.record.chain().medium_angle() > 0)
        image.metadata["pathfarm.mediumAngle"] = std::to_string(j.record.chain().medium_angle() * 180 / kPi);
    if (spec.budget().has_time_seconds())
        image.metadata["pathfarm.timeBudget"] = std::to_string(spec.budget().time_seconds());
    writeEXR((fs::path(jobDir(j.record.id())) / "image.exr").string(), image);
    f.preview = std::make_shared<const Bitmap>(std::move(image));
    f.previewMerged = f.merged;
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
        try {
            writeEXR(image.string(), *f.preview);
        } catch (const SceneError &e) {
            // Still served from memory (preview) until the master restarts.
            spdlog::error("job={}: cannot write the image it got to: {}", j.record.id(), e.what());
        }
    }
    f.block.reset();
    f.chain.reset();
    f.pending.clear();
    f.heldBytes = 0;
    {
        const std::lock_guard<std::mutex> lock(f.spareMu);
        f.spareBlocks.clear();
    }
    fs::remove_all(fs::path(jobDir(j.record.id())) / "results", ec);
}

Bitmap Master::develop(const JobRuntime &j) const {
    if (j.film.chain) return j.film.chain->job->develop();
    return j.film.film->develop(*j.film.block, splatScale(filmPixels(*j.film.film), j.film.spp, j.film.partialPixels));
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
    if (j->film.film)
        out.partialPassShare =
            static_cast<double>(j->film.partialPixels) / static_cast<double>(filmPixels(*j->film.film));
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

}  // namespace pf::master
