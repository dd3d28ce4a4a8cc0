#include "farm/rpc.h"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace pf::farm {

std::shared_ptr<grpc::ServerCredentials> serverCredentials(const TlsFiles &tls) {
    if (tls.cert.empty() && tls.key.empty()) {
        if (!tls.ca.empty())
            throw std::runtime_error("a client CA for mTLS needs the server's own certificate and key");
        return grpc::InsecureServerCredentials();
    }
    if (tls.cert.empty() || tls.key.empty()) throw std::runtime_error("TLS needs both a certificate and a key");
    grpc::SslServerCredentialsOptions opts(tls.ca.empty() ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                                          : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
    opts.pem_root_certs = tls.ca.empty() ? "" : readFile(tls.ca);
    opts.pem_key_cert_pairs.push_back({readFile(tls.key), readFile(tls.cert)});
    return grpc::SslServerCredentials(opts);
}

void listenExclusively(grpc::ServerBuilder &builder, const std::string &address,
                       const std::shared_ptr<grpc::ServerCredentials> &credentials, int *port) {
    builder.AddListeningPort(address, credentials, port);
    builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
}

std::shared_ptr<grpc::Channel> makeChannel(const std::string &address, const TlsFiles &tls, int maxMessageBytes) {
    std::shared_ptr<grpc::ChannelCredentials> creds;
    if (tls.ca.empty() && tls.cert.empty()) {
        creds = grpc::InsecureChannelCredentials();
    } else {
        grpc::SslCredentialsOptions opts;
        if (!tls.ca.empty()) opts.pem_root_certs = readFile(tls.ca);
        if (!tls.cert.empty()) {
            opts.pem_cert_chain = readFile(tls.cert);
            opts.pem_private_key = readFile(tls.key);
        }
        creds = grpc::SslCredentials(opts);
    }
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(maxMessageBytes);
    args.SetMaxSendMessageSize(maxMessageBytes);
    // Not GRPC_ARG_MIN_RECONNECT_BACKOFF_MS: that is also the deadline of a connection attempt, which a
    // TLS handshake on a busy machine can need in full.
    args.SetInt(GRPC_ARG_INITIAL_RECONNECT_BACKOFF_MS, 200);
    args.SetInt(GRPC_ARG_MAX_RECONNECT_BACKOFF_MS, 2000);
    return grpc::CreateCustomChannel(address, creds, args);
}

std::string readFile(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("cannot read " + path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string readToken(const std::string &path) {
    const std::string raw = readFile(path);
    const auto first = raw.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) throw std::runtime_error("token file " + path + " is empty");
    return raw.substr(first, raw.find_last_not_of(" \t\r\n") - first + 1);
}

void setBearer(grpc::ClientContext &ctx, const std::string &token) {
    ctx.AddMetadata("authorization", "Bearer " + token);
}

grpc::Status checkBearer(const grpc::ServerContext &ctx, const std::string &token) {
    const auto &md = ctx.client_metadata();
    const auto it = md.find("authorization");
    const std::string expected = "Bearer " + token;
    if (it == md.end()) return {grpc::StatusCode::UNAUTHENTICATED, "missing bearer token"};
    const std::string_view given(it->second.data(), it->second.size());
    // Constant time in the token's content, so that timing does not reveal a prefix.
    unsigned char diff = given.size() == expected.size() ? 0 : 1;
    for (size_t i = 0; i < expected.size(); ++i)
        diff |= static_cast<unsigned char>(expected[i] ^ (i < given.size() ? given[i] : 0));
    if (diff != 0) return {grpc::StatusCode::UNAUTHENTICATED, "wrong bearer token"};
    return grpc::Status::OK;
}

void setupLogging(const std::string &name, const std::string &level) {
    auto logger = spdlog::stderr_logger_mt(name);
    logger->set_pattern("%Y-%m-%d %H:%M:%S.%e [%n] %l: %v");
    logger->set_level(spdlog::level::from_str(level));
    logger->flush_on(spdlog::level::info);
    spdlog::set_default_logger(logger);
}

}  // namespace pf::farm
