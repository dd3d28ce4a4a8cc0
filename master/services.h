// The master's gRPC services: thin adapters from the wire to Master. Each call checks its bearer token
// first, and every failure becomes a status with a message for the caller (bad input is
// INVALID_ARGUMENT, never a crash).
#pragma once
#include <string>

#include "master.h"
#include "pathfarm/v1/client.grpc.pb.h"
#include "pathfarm/v1/worker.grpc.pb.h"

namespace pf::master {

class ClientService final : public pathfarm::v1::ClientService::Service {
public:
    ClientService(Master &master, std::string token) : master_(master), token_(std::move(token)) {}

    grpc::Status StatBundle(grpc::ServerContext *ctx, const pathfarm::v1::StatBundleRequest *req,
                            pathfarm::v1::StatBundleReply *reply) override;
    grpc::Status UploadBundle(grpc::ServerContext *ctx, grpc::ServerReader<pathfarm::v1::BundleChunk> *reader,
                              pathfarm::v1::UploadBundleReply *reply) override;
    grpc::Status SubmitJob(grpc::ServerContext *ctx, const pathfarm::v1::SubmitJobRequest *req,
                           pathfarm::v1::Job *reply) override;
    grpc::Status GetJob(grpc::ServerContext *ctx, const pathfarm::v1::GetJobRequest *req,
                        pathfarm::v1::Job *reply) override;
    grpc::Status ListJobs(grpc::ServerContext *ctx, const pathfarm::v1::ListJobsRequest *req,
                          pathfarm::v1::ListJobsReply *reply) override;
    grpc::Status WatchJob(grpc::ServerContext *ctx, const pathfarm::v1::WatchJobRequest *req,
                          grpc::ServerWriter<pathfarm::v1::Job> *writer) override;
    grpc::Status CancelJob(grpc::ServerContext *ctx, const pathfarm::v1::CancelJobRequest *req,
                           pathfarm::v1::Job *reply) override;
    grpc::Status FetchImage(grpc::ServerContext *ctx, const pathfarm::v1::FetchImageRequest *req,
                            grpc::ServerWriter<pathfarm::v1::ImageChunk> *writer) override;
    grpc::Status ListWorkers(grpc::ServerContext *ctx, const pathfarm::v1::ListWorkersRequest *req,
                             pathfarm::v1::ListWorkersReply *reply) override;

private:
    Master &master_;
    std::string token_;
};

class WorkerService final : public pathfarm::v1::WorkerService::Service {
public:
    WorkerService(Master &master, std::string token) : master_(master), token_(std::move(token)) {}

    grpc::Status Register(grpc::ServerContext *ctx, const pathfarm::v1::RegisterRequest *req,
                          pathfarm::v1::RegisterReply *reply) override;
    grpc::Status LeaseTask(grpc::ServerContext *ctx, const pathfarm::v1::LeaseRequest *req,
                           pathfarm::v1::LeaseReply *reply) override;
    grpc::Status Heartbeat(grpc::ServerContext *ctx, const pathfarm::v1::HeartbeatRequest *req,
                           pathfarm::v1::HeartbeatReply *reply) override;
    grpc::Status FetchBundle(grpc::ServerContext *ctx, const pathfarm::v1::FetchBundleRequest *req,
                             grpc::ServerWriter<pathfarm::v1::BundleChunk> *writer) override;
    grpc::Status CompleteTask(grpc::ServerContext *ctx, grpc::ServerReader<pathfarm::v1::ResultChunk> *reader,
                              pathfarm::v1::CompleteReply *reply) override;
    grpc::Status FailTask(grpc::ServerContext *ctx, const pathfarm::v1::FailTaskRequest *req,
                          pathfarm::v1::FailTaskReply *reply) override;

private:
    Master &master_;
    std::string token_;
};

}  // namespace pf::master
