#include "compare_report.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pf::client {

using nlohmann::json;

namespace {

Spread spreadOf(const std::vector<double> &v) {
    Spread s;
    if (v.empty()) return s;
    for (double x : v) s.mean += x;
    s.mean /= static_cast<double>(v.size());
    double ss = 0;
    for (double x : v) ss += (x - s.mean) * (x - s.mean);
    s.stddev = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    s.min = *lo;
    s.max = *hi;
    return s;
}

json nameValuesJson(const NameValues &values) {
    json o = json::object();
    for (const auto &[n, v] : values) o[n] = v;
    return o;
}

}  // namespace

const Spread &IntegratorSummary::get(const std::string &name) const {
    for (const auto &[n, s] : quantities)
        if (n == name) return s;
    throw std::out_of_range("no quantity '" + name + "' in the summary");
}

std::vector<IntegratorSummary> summarize(const CompareReport &report) {
    std::vector<IntegratorSummary> out;
    for (const std::string &integrator : report.integrators) {
        std::vector<const RunResult *> runs;
        for (const RunResult &r : report.runs)
            if (r.integrator == integrator) runs.push_back(&r);
        IntegratorSummary s{integrator, static_cast<int>(runs.size()), {}};
        const auto add = [&](const std::string &name, const auto &value) {
            std::vector<double> v;
            for (const RunResult *r : runs) v.push_back(value(*r));
            s.quantities.emplace_back(name, spreadOf(v));
        };
        for (const Metric m : allMetrics()) add(metricName(m), [m](const RunResult &r) { return r.metrics.get(m); });
        add("efficiency", [](const RunResult &r) { return r.efficiency; });
        add("spp", [](const RunResult &r) { return static_cast<double>(r.spp); });
        add("renderSeconds", [](const RunResult &r) { return r.renderSeconds; });
        add("sceneLoadSeconds", [](const RunResult &r) { return r.sceneLoadSeconds; });
        out.push_back(std::move(s));
    }
    return out;
}

json metricsJson(const ErrorMetrics &m) {
    json o;
    for (const Metric k : allMetrics()) o[metricName(k)] = m.get(k);
    o["pixels"] = m.pixels;
    o["trimmedPixels"] = m.trimmedPixels;
    o["epsilon"] = m.options.epsilon;
    o["trimFraction"] = m.options.trimFraction;
    return o;
}

json reportJson(const CompareReport &r) {
    json j;
    j["scene"] = r.scene;
    j["bundleHash"] = r.bundleHash;
    j["farm"] = {{"master", r.master}, {"embedded", r.embeddedFarm}, {"workers", json::array()}};
    for (const WorkerSummary &w : r.workers)
        j["farm"]["workers"].push_back({{"name", w.name}, {"threads", w.threads}, {"cores", w.cores}});
    j["integrators"] = r.integrators;
    j["defines"] = nameValuesJson(r.defines);
    j["params"] = nameValuesJson(r.params);
    j["protocol"] = {{"timeBudgetSeconds", r.timeBudget},
                     {"repetitions", r.repeat},
                     {"seed", r.seed},
                     {"seeds", "repetition k renders with seed + k, the same for every integrator"},
                     {"snapshotTimes", r.snapshotTimes},
                     {"order", "repetition by repetition, the integrators in the order given, one job at a time"}};
    j["width"] = r.width;
    j["height"] = r.height;
    j["exposure"] = r.exposure;
    json defs = json::object();
    for (const Metric m : allMetrics()) defs[metricName(m)] = metricDefinition(m, r.metricOptions.epsilon);
    defs["efficiency"] = "1 / (relmse x renderSeconds)";
    j["metrics"] = {{"epsilon", r.metricOptions.epsilon},
                    {"trimFraction", r.metricOptions.trimFraction},
                    {"trim", r.metricOptions.trimFraction > 0
                                 ? "the highest per-pixel errors (this fraction of the pixels) are discarded from "
                                   "each metric"
                                 : "none"},
                    {"definitions", defs},
                    {"a", "the rendered image"},
                    {"b", "the reference"}};
    j["errorMaps"] = {{"metric", "relmse"}, {"max", r.errorMapMax}, {"scale", "linear, 0 black to max yellow"}};
    j["reference"] = {{"source", r.reference.source},
                      {"exr", r.reference.exr},
                      {"png", r.reference.png},
                      {"cacheFile", r.reference.cacheFile},
                      {"integrator", r.reference.integrator},
                      {"spp", r.reference.spp},
                      {"renderSeconds", r.reference.renderSeconds}};
    j["runs"] = json::array();
    for (const RunResult &run : r.runs) {
        json o = {{"integrator", run.integrator},
                  {"repetition", run.repetition},
                  {"seed", run.seed},
                  {"job", run.job},
                  {"exr", run.exr},
                  {"png", run.png},
                  {"errorPng", run.errorPng},
                  {"spp", run.spp},
                  {"tasks", run.tasks},
                  {"renderSeconds", run.renderSeconds},
                  {"sceneLoadSeconds", run.sceneLoadSeconds},
                  {"workerSceneLoadSeconds", run.workerSceneLoadSeconds},
                  {"metrics", metricsJson(run.metrics)},
                  {"efficiency", run.efficiency},
                  {"snapshots", json::array()}};
        for (const SnapshotResult &s : run.snapshots)
            o["snapshots"].push_back({{"seconds", s.seconds}, {"spp", s.spp}, {"metrics", metricsJson(s.metrics)}});
        j["runs"].push_back(std::move(o));
    }
    j["summary"] = json::array();
    for (const IntegratorSummary &s : summarize(r)) {
        json o = {{"integrator", s.integrator}, {"runs", s.runs}};
        for (const auto &[name, sp] : s.quantities)
            o[name] = {{"mean", sp.mean}, {"stddev", sp.stddev}, {"min", sp.min}, {"max", sp.max}};
        j["summary"].push_back(std::move(o));
    }
    j["crops"] = json::array();
    for (const CropRegion &c : r.crops) {
        json o = {{"x", c.x}, {"y", c.y}, {"size", c.size}, {"png", json::object()}};
        for (const auto &[name, png] : c.pngs) o["png"][name] = png;
        j["crops"].push_back(std::move(o));
    }
    return j;
}

}  // namespace pf::client
