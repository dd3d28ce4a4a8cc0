#include "http_status.h"

#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <sstream>

#include "farm/rpc.h"
#include "image/bitmap.h"

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

std::string prometheus(const MasterMetrics &m) {
    std::ostringstream o;
    auto metric = [&](const char *name, const char *type, const char *help) {
        o << "# HELP " << name << ' ' << help << "\n# TYPE " << name << ' ' << type << '\n';
    };
    metric("pathfarm_tasks", "gauge", "Tasks of the jobs the master knows, by state.");
    for (const auto &[state, n] : m.tasksByState) o << "pathfarm_tasks{state=\"" << state << "\"} " << n << '\n';
    metric("pathfarm_jobs", "gauge", "Jobs by state.");
    for (const auto &[state, n] : m.jobsByState) o << "pathfarm_jobs{state=\"" << state << "\"} " << n << '\n';
    metric("pathfarm_workers", "gauge", "Registered workers; alive ones have been heard from within a lease time.");
    o << "pathfarm_workers{state=\"alive\"} " << m.workersAlive << "\npathfarm_workers{state=\"lost\"} "
      << m.workers - m.workersAlive << '\n';
    metric("pathfarm_samples_per_second", "gauge", "Pixel samples merged per second over the last minute.");
    o << "pathfarm_samples_per_second " << m.samplesPerSecond << '\n';
    metric("pathfarm_samples_merged_total", "counter", "Pixel samples merged since the master started.");
    o << "pathfarm_samples_merged_total " << m.samplesMerged << '\n';
    metric("pathfarm_results_merged_total", "counter", "Task results merged since the master started.");
    o << "pathfarm_results_merged_total " << m.resultsMerged << '\n';
    metric("pathfarm_merge_seconds_total", "counter", "Time spent decoding and merging results.");
    o << "pathfarm_merge_seconds_total " << m.mergeSeconds << '\n';
    metric("pathfarm_result_bytes_total", "counter", "Bytes of accepted result payloads.");
    o << "pathfarm_result_bytes_total " << m.resultBytes << '\n';
    metric("pathfarm_late_results_ignored_total", "counter", "Results of superseded attempts that were ignored.");
    o << "pathfarm_late_results_ignored_total " << m.lateResultsIgnored << '\n';
    metric("pathfarm_attempts_ended_total", "counter", "Attempts that ended without a result.");
    o << "pathfarm_attempts_ended_total{reason=\"expired\"} " << m.attemptsExpired
      << "\npathfarm_attempts_ended_total{reason=\"failed\"} " << m.attemptsFailed << '\n';
    return o.str();
}

// The dashboard: a static page that polls the JSON API once a second.
constexpr const char *kDashboard = R"html(<!doctype html>
<html><head><meta charset="utf-8"><title>pathfarm</title>
<style>
body { font: 14px system-ui, sans-serif; margin: 1.5em; background: #f6f6f4; color: #222; }
h1 { font-size: 1.3em; } h2 { font-size: 1.1em; margin-top: 1.5em; }
table { border-collapse: collapse; background: #fff; } td, th { padding: .3em .7em; border-bottom: 1px solid #ddd; text-align: left; }
.bar { width: 160px; height: 12px; background: #e3e3e3; border-radius: 6px; overflow: hidden; }
.bar > div { height: 100%; background: #3a7bd5; }
#preview { margin-top: 1em; } #preview img { max-width: 512px; image-rendering: pixelated; border: 1px solid #ccc; background: #000; }
</style></head>
<body>
<h1>pathfarm master</h1>
<h2>Jobs</h2>
<table id="jobs"><thead><tr><th>job</th><th>state</th><th>progress</th><th>spp</th><th>integrator</th>
<th>size</th><th>tasks merged</th><th>leased</th><th>seconds</th><th>label</th></tr></thead><tbody></tbody></table>
<div id="preview"></div>
<h2>Workers</h2>
<table id="workers"><thead><tr><th>worker</th><th>name</th><th>state</th><th>threads</th><th>tasks</th>
<th>samples/s</th><th>version</th></tr></thead><tbody></tbody></table>
<script>
const short = s => (s || '').replace(/^(JOB|WORKER)_/, '').toLowerCase();
function row(cells) { const tr = document.createElement('tr');
  for (const c of cells) { const td = document.createElement('td');
    if (c instanceof Node) td.appendChild(c); else td.textContent = c; tr.appendChild(td); } return tr; }
function bar(p) { const b = document.createElement('div'); b.className = 'bar';
  const f = document.createElement('div'); f.style.width = (100 * p).toFixed(1) + '%'; b.appendChild(f); return b; }
let shown = null;
async function refresh() {
  try {
    const jobs = (await (await fetch('/api/v1/jobs')).json()).jobs || [];
    const body = document.querySelector('#jobs tbody'); body.replaceChildren();
    for (const j of jobs.slice().reverse())
      body.appendChild(row([j.id, short(j.state), bar(j.progress || 0), j.samples_per_pixel, j.integrator,
        j.width + 'x' + j.height, j.tasks.merged + '/' + (j.tasks.total > 0 ? j.tasks.total : '?'), j.tasks.leased,
        (j.render_seconds || 0).toFixed(1), j.spec.label || '']));
    const live = jobs.filter(j => Number(j.samples_per_pixel) > 0);
    const pick = live.find(j => short(j.state) == 'running') || live[live.length - 1];
    const box = document.getElementById('preview');
    if (pick) {
      if (shown === null || shown.id != pick.id) { box.innerHTML = '<h2></h2><img alt="preview">'; }
      box.querySelector('h2').textContent = 'Job ' + pick.id + ' (' + short(pick.state) + ', ' + pick.samples_per_pixel + ' spp)';
      if (shown === null || shown.id != pick.id || shown.spp != pick.samples_per_pixel)
        box.querySelector('img').src = '/api/v1/jobs/' + pick.id + '/preview.png?spp=' + pick.samples_per_pixel;
      shown = { id: pick.id, spp: pick.samples_per_pixel };
    }
    const workers = (await (await fetch('/api/v1/workers')).json()).workers || [];
    const wbody = document.querySelector('#workers tbody'); wbody.replaceChildren();
    for (const w of workers)
      wbody.appendChild(row([w.id, w.name, short(w.state), w.threads, w.tasks_completed,
        Number(w.samples_per_second || 0).toPrecision(3), w.version]));
  } catch (e) { console.log(e); }
}
refresh(); setInterval(refresh, 1000);
</script></body></html>
)html";

}  // namespace

HttpStatus::HttpStatus(Master &master, const std::string &listen)
    : master_(master), server_(std::make_unique<httplib::Server>()) {
    httplib::Server &s = *server_;
    s.Get("/", [](const httplib::Request &, httplib::Response &res) { res.set_content(kDashboard, "text/html"); });
    s.Get("/livez", [](const httplib::Request &, httplib::Response &res) { res.set_content("ok\n", "text/plain"); });
    s.Get("/readyz", [this](const httplib::Request &, httplib::Response &res) {
        if (!ready_) res.status = 503;
        res.set_content(ready_ ? "ready\n" : "shutting down\n", "text/plain");
    });
    s.Get("/metrics", [this](const httplib::Request &, httplib::Response &res) {
        res.set_content(prometheus(master_.metrics()), "text/plain; version=0.0.4");
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
    s.set_exception_handler([](const httplib::Request &req, httplib::Response &res, std::exception_ptr ep) {
        try {
            std::rethrow_exception(ep);
        } catch (const std::exception &e) {
            spdlog::error("http {}: {}", req.path, e.what());
        }
        res.status = 500;
        res.set_content("internal error\n", "text/plain");
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
