// pathfarm-master: the farm's master. Serves the client and worker gRPC services (and the standard
// health service) on --listen, the status pages on --http, keeps its state in --data, and resumes every
// unfinished job found there.
#include <malloc.h>
#include <signal.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>

#include "farm/health.h"
#include "farm/rpc.h"
#include "http_status.h"
#include "master.h"
#include "services.h"

namespace {

struct Args {
    std::string listen = "127.0.0.1:7700", http, data = "pathfarm-data", tokenFile, workerTokenFile, logLevel = "info";
    pf::farm::TlsFiles tls;
    int64_t leaseMs = 10000, heartbeatMs = 3000, checkpointMs = 10000, batchWindowMs = 1000;
    int maxMessageMiB = 4;
    int64_t maxBundleMiB = 2048;
};

int run(const Args &a, pf::master::MasterConfig cfg) {
    // Every result passes through buffers of megabytes (payload, decompressed arrays, film block).
    // glibc maps blocks above 128 KiB afresh and unmaps them on free, and the page faults of the next
    // mapping cost more than decoding (bench_farm, 256x256 results: 25 -> 14 ms of master CPU each):
    // such buffers are reused from the heap instead, which keeps up to the trim threshold of free memory.
    mallopt(M_MMAP_THRESHOLD, 64 << 20);
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
    // Signals are taken by sigwait in this thread; every thread started from here inherits the mask.
    sigset_t stopSignals;
    sigemptyset(&stopSignals);
    sigaddset(&stopSignals, SIGTERM);
    sigaddset(&stopSignals, SIGINT);
    pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);

    const std::string clientToken = pf::farm::readToken(a.tokenFile);
    const std::string workerToken = pf::farm::readToken(a.workerTokenFile);
    if (clientToken == workerToken) throw std::runtime_error("the client and worker tokens must differ");
    pf::master::Master master(std::move(cfg));
    pf::master::ClientService clientService(master, clientToken);
    pf::master::WorkerService workerService(master, workerToken);

    pf::farm::HealthService health;
    grpc::ServerBuilder builder;
    int port = 0;
    pf::farm::listenExclusively(builder, a.listen, pf::farm::serverCredentials(a.tls), &port);
    builder.SetMaxReceiveMessageSize(master.config().maxMessageBytes);
    builder.SetMaxSendMessageSize(master.config().maxMessageBytes);
    builder.RegisterService(&clientService);
    builder.RegisterService(&workerService);
    builder.RegisterService(&health);
    const std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
    if (!server || port == 0) throw std::runtime_error("cannot listen on " + a.listen);
    spdlog::info("listening on {} (port {}), data in {}, TLS {}", a.listen, port, master.config().dataDir,
                 a.tls.cert.empty() ? "off" : (a.tls.ca.empty() ? "on" : "on, client certificates required"));
    std::unique_ptr<pf::master::HttpStatus> status;
    if (!a.http.empty()) {
        status = std::make_unique<pf::master::HttpStatus>(master, a.http);
        spdlog::info("HTTP status on {} (port {})", a.http, status->port());
    }

    int sig = 0;
    sigwait(&stopSignals, &sig);
    spdlog::info("signal {}: shutting down", sig);
    health.setServing(false);
    if (status) status->setUnready();
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
    return 0;
}

}  // namespace

int main(int argc, char **argv) {
    CLI::App app{"pathfarm-master: schedules render jobs over pathfarm workers"};
    Args a;
    pf::master::MasterConfig cfg;
    app.add_option("--listen", a.listen, "gRPC address (host:port) for clients and workers")->capture_default_str();
    app.add_option("--http", a.http, "HTTP address (host:port) of the status pages, /metrics and the dashboard");
    app.add_option("--data", a.data, "Directory of the job store, bundles and films")->capture_default_str();
    app.add_option("--token-file", a.tokenFile, "File holding the clients' bearer token")->required();
    app.add_option("--worker-token-file", a.workerTokenFile, "File holding the workers' bearer token")->required();
    app.add_option("--tls-cert", a.tls.cert, "PEM certificate: serve TLS");
    app.add_option("--tls-key", a.tls.key, "PEM private key of --tls-cert");
    app.add_option("--tls-client-ca", a.tls.ca, "PEM CA: require client certificates signed by it (mTLS)");
    app.add_option("--lease-ms", a.leaseMs, "Lease time: a task whose worker is silent this long is re-leased")
        ->check(CLI::Range(int64_t(100), int64_t(3600000)))
        ->capture_default_str();
    app.add_option("--heartbeat-ms", a.heartbeatMs, "How often workers renew their leases")
        ->check(CLI::Range(int64_t(20), int64_t(600000)))
        ->capture_default_str();
    app.add_option("--checkpoint-ms", a.checkpointMs, "Minimum time between film checkpoints of a job")
        ->check(CLI::Range(int64_t(0), int64_t(3600000)))
        ->capture_default_str();
    app.add_option("--max-message-mib", a.maxMessageMiB, "gRPC message size limit")
        ->check(CLI::Range(1, 1024))
        ->capture_default_str();
    app.add_option("--max-pixels", cfg.maxPixels, "Per-job limit on the rendered pixels")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--max-spp", cfg.maxSpp, "Per-job limit on samples per pixel")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--max-time", cfg.maxTimeSeconds, "Per-job limit on a time budget (seconds)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--max-bundle-mib", a.maxBundleMiB, "Limit on a scene bundle")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--max-failures-per-worker", cfg.maxFailuresPerWorker,
                   "Failed or expired attempts of one job after which a worker is blocklisted for it")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--max-failures-per-task", cfg.maxFailuresPerTask, "Failed attempts of one task that fail its job")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--batch-busy", cfg.batchBusyShare,
                   "Workers with --batch auto get batches of tasks while taking results uses more than this "
                   "share of one master core")
        ->check(CLI::Range(0.0, 64.0))
        ->capture_default_str();
    app.add_option("--batch-window-ms", a.batchWindowMs, "How often the batch for --batch auto workers may change")
        ->check(CLI::Range(10, 60000))
        ->capture_default_str();
    app.add_option("--log-level", a.logLevel, "trace, debug, info, warn, error")->capture_default_str();
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError &e) {
        return app.exit(e);
    }
    pf::farm::setupLogging("master", a.logLevel);
    cfg.leaseTime = std::chrono::milliseconds(a.leaseMs);
    cfg.heartbeat = std::chrono::milliseconds(a.heartbeatMs);
    cfg.checkpointInterval = std::chrono::milliseconds(a.checkpointMs);
    cfg.batchWindow = std::chrono::milliseconds(a.batchWindowMs);
    cfg.maxMessageBytes = a.maxMessageMiB << 20;
    cfg.maxBundleBytes = static_cast<uint64_t>(a.maxBundleMiB) << 20;
    try {
        // The store records the paths of result and checkpoint files as they are made from the data
        // directory; a relative one would name other files once the master restarts in another working
        // directory (and fail the job it resumes).
        cfg.dataDir = std::filesystem::weakly_canonical(std::filesystem::absolute(a.data)).string();
        return run(a, std::move(cfg));
    } catch (const std::exception &e) {
        spdlog::critical("{}", e.what());
        return 1;
    }
}
