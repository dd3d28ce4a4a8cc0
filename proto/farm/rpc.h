// What the master, the workers and the client share about talking gRPC: credentials (TLS, mTLS),
// bearer tokens, channel settings and logging.
#pragma once
#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

namespace pf::farm {

// Reported by workers at registration and by `pathfarm health`.
inline constexpr const char *kVersion = "0.1.0";

// LeaseRequest.max_tasks of a worker that leaves its batch size to the master (master/batch_governor.h).
inline constexpr int kAutoBatch = -1;

// PEM files. A server uses TLS when cert and key are given and then requires client certificates
// signed by `ca` when that is given too (mTLS). A client uses TLS when `ca` (the roots it trusts) is
// given, presenting cert and key when those are given.
struct TlsFiles {
    std::string cert, key, ca;
};

std::shared_ptr<grpc::ServerCredentials> serverCredentials(const TlsFiles &tls);

// Adds a listening port on `address` that no other socket may share: gRPC binds with SO_REUSEPORT by
// default, with which a second master (or worker health service) on the same address would start and
// take part of the connections instead of failing. `*port` is set once the server is built (0: failed).
void listenExclusively(grpc::ServerBuilder &builder, const std::string &address,
                       const std::shared_ptr<grpc::ServerCredentials> &credentials, int *port);

// A channel with the message size limit in both directions and short reconnect backoff, so that
// workers and clients find a restarted master within seconds.
std::shared_ptr<grpc::Channel> makeChannel(const std::string &address, const TlsFiles &tls, int maxMessageBytes);

// A whole file; throws std::runtime_error naming it when it cannot be read.
std::string readFile(const std::string &path);
// A token file: its content without surrounding whitespace; throws if missing or empty.
std::string readToken(const std::string &path);

// Bearer tokens: every call carries `authorization: Bearer <token>`.
void setBearer(grpc::ClientContext &ctx, const std::string &token);
// OK when the call carries exactly `token` (compared in constant time), UNAUTHENTICATED otherwise.
grpc::Status checkBearer(const grpc::ServerContext &ctx, const std::string &token);

// Logs to stderr as "time [name] level message"; `level` is spdlog's (trace, debug, info, warn, ...).
void setupLogging(const std::string &name, const std::string &level);

}  // namespace pf::farm
