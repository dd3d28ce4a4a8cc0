#include "http_status.h"

#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <spdlog/spdlog.h>

#include <filesystem>

#include "dashboard.h"
#include "farm/rpc.h"
#include "image/bitmap.h"
#include "prometheus.h"

namespace pf::master {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

std::string toJson(const google::protobuf::Message &m) {
    google::protobuf::util::JsonPrintOptions opts;
    opts.preserve_proto_field_names = true;
    opts.always_print_primitive_fields = true;
    std::string json;
    if (!google::protobuf::util::MessageToJsonString(m, &json, opts).ok()) return "{}";
    return json;
}

constexpr size_t kHttpThreads = 64;

}  // namespace

HttpStatus::HttpStatus(Master &master, const std::string &listen)
    : master_(master), server_(std::make_unique<httplib::Server>()) {
    httplib::Server &s = *server_;
    s.Get("/", [](const httplib::Request &, httplib::Response &res) {
        const std::string_view page = dashboardPage();
        res.set_content(page.data(), page.size(), "text/html; charset=utf-8");
    });
    s.Get("/livez", [](const httplib::Request &, httplib::Response &res) { res.set_content("ok\n", "text/plain"); });
    s.Get("/readyz", [this](const httplib::Request &, httplib::Response &res) {
        if (!ready_) res.status = 503;
        res.set_content(ready_ ? "ready\n" : "shutting down\n", "text/plain");
    });
    s.Get("/metrics", [this](const httplib::Request &, httplib::Response &res) {
        res.set_content(prometheusText(master_.metrics(), master_.jobs(), master_.workers()),
                        "text/plain; version=0.0.4");
    });
    s.Get("/api/v1/jobs", [this](const httplib::Request &, httplib::Response &res) {
        v1::ListJobsReply reply;
        for (v1::Job &j : master_.jobs()) *reply.add_jobs() = std::move(j);
        res.set_content(toJson(reply), "application/json");
    });
    s.Get(R"(/api/v1/jobs/(\d+))", [this](const httplib::Request &req, httplib::Response &res) {
        const auto job = master_.job(std::stoll(req.matches[1]));
        if (!job) {
            res.status = 404;
            res.set_content("{\"error\": \"no such job\"}", "application/json");
            return;
        }
        res.set_content(toJson(*job), "application/json");
    });
    s.Get(R"(/api/v1/jobs/(\d+)/preview.png)", [this](const httplib::Request &req, httplib::Response &res) {
        const auto preview = master_.preview(std::stoll(req.matches[1]));
        if (!preview) {
            res.status = 404;
            res.set_content("no preview yet\n", "text/plain");
            return;
        }
        // writePNG writes files only; each request goes through a private temporary one.
        static std::atomic<uint64_t> counter{0};
        const fs::path tmp = fs::path(master_.config().dataDir) / ("preview-" + std::to_string(counter++) + ".png");
        writePNG(tmp.string(), *preview);
        res.set_content(farm::readFile(tmp.string()), "image/png");
        std::error_code ec;
        fs::remove(tmp, ec);
    });
    s.Get("/api/v1/workers", [this](const httplib::Request &, httplib::Response &res) {
        v1::ListWorkersReply reply;
        for (v1::WorkerInfo &w : master_.workers()) *reply.add_workers() = std::move(w);
        res.set_content(toJson(reply), "application/json");
    });
    // Everything here changes as the farm runs: no cache may answer for the master.
    // A connection holds one of the pool's threads until its request is read: slow or silent clients
    // (slowloris) would otherwise take httplib's default of 8 threads for 5 s each and stall the status
    // pages for everyone (tests/test_farm_hostile.cpp). Idle threads cost only their stacks.
    s.new_task_queue = [] { return new httplib::ThreadPool(kHttpThreads); };
    s.set_read_timeout(2, 0);
    s.set_write_timeout(5, 0);
    s.set_keep_alive_timeout(2);
    s.set_payload_max_length(1 << 20);  // the status pages take no bodies; a large one is refused (413)
    s.set_post_routing_handler(
        [](const httplib::Request &, httplib::Response &res) { res.set_header("Cache-Control", "no-store"); });
    s.set_exception_handler([](const httplib::Request &req, httplib::Response &res, std::exception_ptr ep) {
        try {
            std::rethrow_exception(ep);
        } catch (const std::exception &e) {
            spdlog::error("http {}: {}", req.path, e.what());
        }
        res.status = 500;
        res.set_content("internal error\n", "text/plain");
    });

    // httplib's default sets SO_REUSEPORT, with which the status port could be shared with another
    // listener (even this master's gRPC port) and requests would go to either. SO_REUSEADDR alone still
    // lets a restarted master rebind a port whose old connections are in TIME_WAIT.
    s.set_socket_options([](socket_t sock) {
        const int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });

    const auto colon = listen.rfind(':');
    if (colon == std::string::npos) throw std::runtime_error("--http wants host:port, got '" + listen + "'");
    const std::string host = listen.substr(0, colon);
    const int port = std::stoi(listen.substr(colon + 1));
    port_ = port == 0 ? s.bind_to_any_port(host) : (s.bind_to_port(host, port) ? port : -1);
    if (port_ <= 0) throw std::runtime_error("cannot listen on " + listen + " for HTTP");
    thread_ = std::thread([this] { server_->listen_after_bind(); });
}

HttpStatus::~HttpStatus() {
    server_->stop();
    thread_.join();
}

}  // namespace pf::master
