// The master's status over HTTP (read-only): JSON under /api/v1/ (the proto messages printed as JSON),
// Prometheus text at /metrics, /livez and /readyz for orchestrators, and a dashboard at / with jobs,
// progress bars, workers and a live preview of the running image. It carries no credentials and changes
// nothing, so it may face a browser; bind it to an address accordingly.
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <thread>

#include "master.h"

namespace httplib {
class Server;
}

namespace pf::master {

class HttpStatus {
public:
    // Serves on host:port (port 0: any free port) from a thread of its own until destroyed.
    HttpStatus(Master &master, const std::string &listen);
    ~HttpStatus();
    HttpStatus(const HttpStatus &) = delete;
    HttpStatus &operator=(const HttpStatus &) = delete;

    int port() const { return port_; }
    // /readyz answers 503 from now on (the master is shutting down).
    void setUnready() { ready_ = false; }

private:
    Master &master_;
    std::unique_ptr<httplib::Server> server_;
    int port_ = 0;
    std::atomic<bool> ready_{true};
    std::thread thread_;
};

}  // namespace pf::master
