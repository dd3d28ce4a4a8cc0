// pathfarm-worker: renders tasks leased from a pathfarm master. SIGTERM (or SIGINT) drains: the task in
// hand is finished and delivered, then the worker exits (code 1 when the master stayed silent for a
// lease time and results were abandoned); a second signal exits at once (the master re-leases the task
// when its lease runs out).
#include <signal.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdlib>

#include "cpu_quota.h"
#include "farm/health.h"
#include "worker.h"

int main(int argc, char **argv) {
    CLI::App app{"pathfarm-worker: renders tasks for a pathfarm master"};
    pf::worker::WorkerConfig cfg;
    std::string tokenFile, healthListen = "127.0.0.1:0", logLevel = "info";
    if (const char *m = std::getenv("PATHFARM_MASTER")) cfg.master = m;
    cfg.threads = pf::worker::availableCores();
    cfg.name = [] {
        char host[256] = {};
        gethostname(host, sizeof host - 1);
        return std::string(host) + ":" + std::to_string(getpid());
    }();
    app.add_option("--master", cfg.master, "Master address host:port (default: $PATHFARM_MASTER)")
        ->capture_default_str();
    app.add_option("--token-file", tokenFile, "File holding the workers' bearer token")->required();
    app.add_option("--threads", cfg.threads, "Render threads (default: the cores this process may use)")
        ->check(CLI::Range(1, 4096))
        ->capture_default_str();
    app.add_option("--cache", cfg.cacheDir, "Directory of cached scene bundles")->capture_default_str();
    app.add_option("--name", cfg.name, "Name shown in listings")->capture_default_str();
    app.add_option("--tls-ca", cfg.tls.ca, "PEM CA: connect with TLS, trusting these roots");
    app.add_option("--tls-cert", cfg.tls.cert, "PEM client certificate (mTLS)");
    app.add_option("--tls-key", cfg.tls.key, "PEM private key of --tls-cert");
    app.add_option("--health-listen", healthListen, "Address of this worker's gRPC health service (port 0: any)")
        ->capture_default_str();
    app.add_option("--log-level", logLevel, "trace, debug, info, warn, error")->capture_default_str();
    std::string batch = "auto";
    app.add_option("--batch", batch,
                   "Tasks leased at once and returned as one result (image tasks, or a Markov-chain job's chain "
                   "tasks; less master CPU and fewer bytes per task): 1..1024 (the master holds image batches "
                   "to 64 tasks), or auto, where the master batches only while taking results keeps it busy. Only "
                   "batches of one give an image equal to the embedded render bit for bit")
        ->check(CLI::IsMember({"auto"}) | CLI::Range(1, 1024))
        ->capture_default_str();
    app.add_flag("--fail-every-task", cfg.failEveryTask, "Test-only fault injection: fail every leased task")
        ->group("");
    app.add_option("--upload-delay", cfg.uploadDelaySeconds, "Test-only: seconds to wait before each upload")
        ->check(CLI::Range(0.0, 60.0))
        ->group("");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError &e) {
        return app.exit(e);
    }
    cfg.batch = batch == "auto" ? pf::farm::kAutoBatch : std::stoi(batch);
    pf::farm::setupLogging("worker", logLevel);

    sigset_t stopSignals;
    sigemptyset(&stopSignals);
    sigaddset(&stopSignals, SIGTERM);
    sigaddset(&stopSignals, SIGINT);
    pthread_sigmask(SIG_BLOCK, &stopSignals, nullptr);
    try {
        cfg.token = pf::farm::readToken(tokenFile);
        pf::worker::Worker worker(cfg);

        pf::farm::HealthService healthService;
        grpc::ServerBuilder builder;
        int port = 0;
        pf::farm::listenExclusively(builder, healthListen, grpc::InsecureServerCredentials(), &port);
        builder.RegisterService(&healthService);
        const std::unique_ptr<grpc::Server> health = builder.BuildAndStart();
        if (!health || port == 0) throw std::runtime_error("cannot listen on " + healthListen);
        spdlog::info("health service on port {}", port);

        std::thread signals([&] {
            int sig = 0;
            sigwait(&stopSignals, &sig);
            spdlog::info("signal {}: draining (a second signal exits at once)", sig);
            healthService.setServing(false);
            worker.drain();
            sigwait(&stopSignals, &sig);
            std::_Exit(128 + sig);
        });
        signals.detach();
        const int code = worker.run();
        health->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
        return code;
    } catch (const std::exception &e) {
        spdlog::critical("{}", e.what());
        return 1;
    }
}
