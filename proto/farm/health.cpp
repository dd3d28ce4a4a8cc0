#include "farm/health.h"

#include <chrono>
#include <thread>

namespace pf::farm {

using grpc::health::v1::HealthCheckResponse;

// The whole server ("") is the only service name answered; the protocol says others are unknown.
HealthCheckResponse::ServingStatus HealthService::status(const std::string &service) const {
    if (!service.empty()) return HealthCheckResponse::SERVICE_UNKNOWN;
    return serving_ ? HealthCheckResponse::SERVING : HealthCheckResponse::NOT_SERVING;
}

grpc::Status HealthService::Check(grpc::ServerContext *, const grpc::health::v1::HealthCheckRequest *req,
                                  HealthCheckResponse *reply) {
    const auto s = status(req->service());
    if (s == HealthCheckResponse::SERVICE_UNKNOWN) return {grpc::StatusCode::NOT_FOUND, "unknown service"};
    reply->set_status(s);
    return grpc::Status::OK;
}

grpc::Status HealthService::Watch(grpc::ServerContext *ctx, const grpc::health::v1::HealthCheckRequest *req,
                                  grpc::ServerWriter<HealthCheckResponse> *writer) {
    HealthCheckResponse reply;
    reply.set_status(status(req->service()));
    if (!writer->Write(reply)) return grpc::Status::OK;
    // Status changes are rare (shutdown, drain): polling keeps this free of extra synchronization.
    while (!ctx->IsCancelled()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        if (status(req->service()) == reply.status()) continue;
        reply.set_status(status(req->service()));
        if (!writer->Write(reply)) break;
    }
    return grpc::Status::OK;
}

}  // namespace pf::farm
