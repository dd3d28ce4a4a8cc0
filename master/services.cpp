#include "services.h"

#include <spdlog/spdlog.h>

#include <thread>

#include "core/error.h"
#include "farm/error.h"
#include "farm/result_stream.h"
#include "farm/rpc.h"

namespace pf::master {

namespace v1 = pathfarm::v1;
using grpc::Status;
using grpc::StatusCode;

namespace {

// Runs a handler after the token check, turning every exception into a status: user errors name
// their cause, anything else is logged and reported as internal.
template <typename F>
Status handle(grpc::ServerContext *ctx, const std::string &token, const char *method, F &&body) {
    if (Status s = farm::checkBearer(*ctx, token); !s.ok()) {
        spdlog::warn("{} from {}: refused: {}", method, ctx->peer(), s.error_message());
        return s;
    }
    try {
        return body();
    } catch (const farm::FarmError &e) {
        return {StatusCode::INVALID_ARGUMENT, e.what()};
    } catch (const SceneError &e) {
        return {StatusCode::INVALID_ARGUMENT, e.what()};
    } catch (const UnknownWorker &e) {
        return {StatusCode::NOT_FOUND, e.what()};
    } catch (const StorageError &e) {
        // Worth repeating once the data directory has room again: workers retry UNAVAILABLE.
        spdlog::error("{} from {}: {}", method, ctx->peer(), e.what());
        return {StatusCode::UNAVAILABLE, std::string("master storage: ") + e.what()};
    } catch (const std::exception &e) {
        spdlog::error("{} from {}: {}", method, ctx->peer(), e.what());
        return {StatusCode::INTERNAL, e.what()};
    }
}

Status noSuchJob(int64_t id) { return {StatusCode::NOT_FOUND, "no job " + std::to_string(id)}; }

// Chunks below the message limit, leaving room for the envelope.
size_t chunkBytes(const Master &m) { return static_cast<size_t>(std::min(1 << 20, m.config().maxMessageBytes - 4096)); }

}  // namespace

// ---- client service ----

Status ClientService::StatBundle(grpc::ServerContext *ctx, const v1::StatBundleRequest *req,
                                 v1::StatBundleReply *reply) {
    return handle(ctx, token_, "StatBundle", [&] {
        reply->set_present(master_.bundles().has(req->hash()));
        return Status::OK;
    });
}

Status ClientService::UploadBundle(grpc::ServerContext *ctx, grpc::ServerReader<v1::BundleChunk> *reader,
                                   v1::UploadBundleReply *reply) {
    return handle(ctx, token_, "UploadBundle", [&] {
        uint64_t bytes = 0;
        const std::string hash = master_.bundles().receive([&](v1::BundleChunk &c) {
            if (!reader->Read(&c)) return false;
            bytes += c.data().size();
            return true;
        });
        spdlog::info("bundle {}: stored from {} ({} bytes received)", hash, ctx->peer(), bytes);
        reply->set_hash(hash);
        reply->set_bytes(bytes);
        return Status::OK;
    });
}

Status ClientService::SubmitJob(grpc::ServerContext *ctx, const v1::SubmitJobRequest *req, v1::Job *reply) {
    return handle(ctx, token_, "SubmitJob", [&] {
        try {
            *reply = master_.submit(req->spec());
        } catch (const std::exception &e) {
            spdlog::warn("SubmitJob from {}: refused: {}", ctx->peer(), e.what());
            throw;
        }
        return Status::OK;
    });
}

Status ClientService::GetJob(grpc::ServerContext *ctx, const v1::GetJobRequest *req, v1::Job *reply) {
    return handle(ctx, token_, "GetJob", [&] {
        const auto job = master_.job(req->id());
        if (!job) return noSuchJob(req->id());
        *reply = *job;
        return Status::OK;
    });
}

Status ClientService::ListJobs(grpc::ServerContext *ctx, const v1::ListJobsRequest *, v1::ListJobsReply *reply) {
    return handle(ctx, token_, "ListJobs", [&] {
        for (v1::Job &j : master_.jobs()) *reply->add_jobs() = std::move(j);
        return Status::OK;
    });
}

Status ClientService::WatchJob(grpc::ServerContext *ctx, const v1::WatchJobRequest *req,
                               grpc::ServerWriter<v1::Job> *writer) {
    return handle(ctx, token_, "WatchJob", [&] {
        std::string last;
        for (uint64_t seen = master_.changeCount();;) {
            const auto job = master_.job(req->id());
            if (!job) return noSuchJob(req->id());
            // The running time grows by itself; only real changes are sent.
            v1::Job compare = *job;
            compare.clear_render_seconds();
            compare.clear_progress();
            std::string now = compare.SerializeAsString();
            if (now != last && !writer->Write(*job)) return Status::OK;
            last = std::move(now);
            if (job->state() != v1::JOB_QUEUED && job->state() != v1::JOB_RUNNING) return Status::OK;
            if (ctx->IsCancelled()) return Status::CANCELLED;
            // At most a few updates a second, however fast results merge.
            std::this_thread::sleep_for(std::chrono::milliseconds(200));
            seen = master_.waitForChange(seen, std::chrono::seconds(1));
        }
    });
}

Status ClientService::CancelJob(grpc::ServerContext *ctx, const v1::CancelJobRequest *req, v1::Job *reply) {
    return handle(ctx, token_, "CancelJob", [&] {
        const auto job = master_.cancel(req->id());
        if (!job) return noSuchJob(req->id());
        *reply = *job;
        return Status::OK;
    });
}

Status ClientService::FetchImage(grpc::ServerContext *ctx, const v1::FetchImageRequest *req,
                                 grpc::ServerWriter<v1::ImageChunk> *writer) {
    return handle(ctx, token_, "FetchImage", [&] {
        const auto image = master_.image(req->id());
        if (!image) {
            if (!master_.job(req->id())) return noSuchJob(req->id());
            return Status(StatusCode::FAILED_PRECONDITION, "job " + std::to_string(req->id()) + " has no image yet");
        }
        v1::ImageChunk chunk;
        chunk.mutable_info()->set_size(image->bytes.size());
        chunk.mutable_info()->set_final(image->final);
        chunk.mutable_info()->set_samples_per_pixel(image->samplesPerPixel);
        chunk.mutable_info()->set_partial_pass_share(image->partialPassShare);
        if (!writer->Write(chunk)) return Status::OK;
        const size_t step = chunkBytes(master_);
        for (size_t off = 0; off < image->bytes.size(); off += step) {
            chunk.set_data(image->bytes.substr(off, step));
            if (!writer->Write(chunk)) return Status::OK;
        }
        return Status::OK;
    });
}

Status ClientService::ListWorkers(grpc::ServerContext *ctx, const v1::ListWorkersRequest *,
                                  v1::ListWorkersReply *reply) {
    return handle(ctx, token_, "ListWorkers", [&] {
        for (v1::WorkerInfo &w : master_.workers()) *reply->add_workers() = std::move(w);
        return Status::OK;
    });
}

// ---- worker service ----

Status WorkerService::Register(grpc::ServerContext *ctx, const v1::RegisterRequest *req, v1::RegisterReply *reply) {
    return handle(ctx, token_, "Register", [&] {
        *reply = master_.registerWorker(*req, ctx->peer());
        return Status::OK;
    });
}

Status WorkerService::LeaseTask(grpc::ServerContext *ctx, const v1::LeaseRequest *req, v1::LeaseReply *reply) {
    return handle(ctx, token_, "LeaseTask", [&] {
        spdlog::debug("worker={}: LeaseTask", req->worker_id());
        std::vector<v1::TaskSpec> tasks = master_.lease(
            req->worker_id(), std::chrono::milliseconds(std::max<int64_t>(0, req->wait_ms())), req->max_tasks());
        for (size_t i = 0; i < tasks.size(); ++i)
            *(i == 0 ? reply->mutable_task() : reply->add_more()) = std::move(tasks[i]);
        return Status::OK;
    });
}

Status WorkerService::Heartbeat(grpc::ServerContext *ctx, const v1::HeartbeatRequest *req, v1::HeartbeatReply *reply) {
    return handle(ctx, token_, "Heartbeat", [&] {
        const std::vector<int64_t> held(req->attempt_ids().begin(), req->attempt_ids().end());
        for (const int64_t a : master_.heartbeat(req->worker_id(), held, req->draining()))
            reply->add_lost_attempt_ids(a);
        return Status::OK;
    });
}

Status WorkerService::FetchBundle(grpc::ServerContext *ctx, const v1::FetchBundleRequest *req,
                                  grpc::ServerWriter<v1::BundleChunk> *writer) {
    return handle(ctx, token_, "FetchBundle", [&] {
        if (!master_.bundles().has(req->hash()))
            return Status(StatusCode::NOT_FOUND, "no bundle '" + req->hash().substr(0, 64) + "'");
        farm::streamBundle(master_.bundles().dir(req->hash()), master_.bundles().manifest(req->hash()),
                           chunkBytes(master_), [&](const v1::BundleChunk &c) { return writer->Write(c); });
        return Status::OK;
    });
}

Status WorkerService::CompleteTask(grpc::ServerContext *ctx, grpc::ServerReader<v1::ResultChunk> *reader,
                                   v1::CompleteReply *reply) {
    return handle(ctx, token_, "CompleteTask", [&] {
        const auto read = [&](v1::ResultChunk &c) { return reader->Read(&c); };
        const v1::ResultHeader header = farm::readResultHeader(read);
        spdlog::debug("attempt={} worker={}: CompleteTask, {} bytes", header.attempt_id(), header.worker_id(),
                      header.payload_size());
        if (header.batch_attempt_ids_size() >= Master::kMaxChainBatchTasks)
            throw farm::FarmError("CompleteTask: a batch of more than " + std::to_string(Master::kMaxChainBatchTasks) +
                                  " tasks");
        std::vector<int64_t> attempts{header.attempt_id()};
        attempts.insert(attempts.end(), header.batch_attempt_ids().begin(), header.batch_attempt_ids().end());
        // A stale result is refused before its payload is read.
        for (const int64_t a : attempts)
            if (const std::string reason = master_.checkAttempt(header.worker_id(), a); !reason.empty()) {
                *reply = master_.ignoreResult(header.worker_id(), a, reason);
                return Status::OK;
            }
        const std::string payload = farm::readResultPayload(header, master_.maxPayloadBytes(header.attempt_id()), read);
        *reply = master_.complete(header.worker_id(), attempts, header.stats(), payload);
        return Status::OK;
    });
}

Status WorkerService::FailTask(grpc::ServerContext *ctx, const v1::FailTaskRequest *req, v1::FailTaskReply *) {
    return handle(ctx, token_, "FailTask", [&] {
        master_.fail(req->worker_id(), req->attempt_id(), req->error(), req->released());
        return Status::OK;
    });
}

}  // namespace pf::master
