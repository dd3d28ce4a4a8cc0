// The standard gRPC health service (grpc.health.v1) for master and worker: SERVING while the process
// takes work, NOT_SERVING once it shuts down or drains. Implemented here rather than through gRPC's
// built-in one, which needs another synchronous service on the same server (a worker has none).
#pragma once
#include <atomic>

#include "grpc/health/v1/health.grpc.pb.h"

namespace pf::farm {

class HealthService final : public grpc::health::v1::Health::Service {
public:
    void setServing(bool serving) { serving_ = serving; }

    grpc::Status Check(grpc::ServerContext *ctx, const grpc::health::v1::HealthCheckRequest *req,
                       grpc::health::v1::HealthCheckResponse *reply) override;
    grpc::Status Watch(grpc::ServerContext *ctx, const grpc::health::v1::HealthCheckRequest *req,
                       grpc::ServerWriter<grpc::health::v1::HealthCheckResponse> *writer) override;

private:
    grpc::health::v1::HealthCheckResponse::ServingStatus status(const std::string &service) const;
    std::atomic<bool> serving_{true};
};

}  // namespace pf::farm
