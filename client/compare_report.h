// What `pathfarm compare` measured, and its summary over repetitions: the data behind report.json and
// index.html. Every number of the page is in the JSON.
#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "farm/job_setup.h"
#include "image/metrics.h"

namespace pf::client {

// The image at one point of a run: for the convergence plots.
struct SnapshotResult {
    double seconds = 0;
    int64_t spp = 0;
    ErrorMetrics metrics;
};

// One job of the comparison: an integrator at one repetition (its own seed).
struct RunResult {
    std::string integrator;
    int repetition = 0;
    uint64_t seed = 0;
    int64_t job = 0;
    std::string exr, png, errorPng;  // files relative to the report's directory
    int64_t spp = 0, tasks = 0;
    double renderSeconds = 0;           // true time: first lease to last merge
    double sceneLoadSeconds = 0;        // the master's load and BVH build, apart from rendering
    double workerSceneLoadSeconds = 0;  // workers' bundle fetches and loads, within renderSeconds
    ErrorMetrics metrics;
    double efficiency = 0;  // 1 / (relMSE x renderSeconds)
    std::vector<SnapshotResult> snapshots;
};

struct ReferenceInfo {
    std::string source;  // "file" (--reference), "rendered" or "cache" (--reference-spp)
    std::string exr, png, cacheFile, integrator;
    int64_t spp = 0;
    double renderSeconds = 0;
};

struct WorkerSummary {
    std::string name;
    int threads = 0, cores = 0;
};

// A zoomed region, the same for every image: PNG crops named by integrator ("reference" too).
struct CropRegion {
    int x = 0, y = 0, size = 0;
    std::vector<std::pair<std::string, std::string>> pngs;
};

struct CompareReport {
    std::string scene, bundleHash, master;
    bool embeddedFarm = false;
    std::vector<WorkerSummary> workers;
    std::vector<std::string> integrators;
    NameValues defines, params;
    double timeBudget = 0;
    int repeat = 0;
    uint64_t seed = 0;
    std::vector<double> snapshotTimes;
    int width = 0, height = 0;
    double exposure = 0;     // stops, applied to every PNG
    double errorMapMax = 0;  // per-pixel relMSE at the brightest colour of every error map
    MetricOptions metricOptions;
    ReferenceInfo reference;
    std::vector<RunResult> runs;
    std::vector<CropRegion> crops;
};

// Mean and spread (sample standard deviation; 0 for a single run) of one quantity over repetitions.
struct Spread {
    double mean = 0, stddev = 0, min = 0, max = 0;
};
// One integrator's runs summarized: quantity name -> spread. Quantities: the metric names, "efficiency",
// "spp", "renderSeconds", "sceneLoadSeconds".
struct IntegratorSummary {
    std::string integrator;
    int runs = 0;
    std::vector<std::pair<std::string, Spread>> quantities;
    const Spread &get(const std::string &name) const;
};
std::vector<IntegratorSummary> summarize(const CompareReport &report);

// The metrics of one image as JSON: every metric by name, with the epsilon and the trim.
nlohmann::json metricsJson(const ErrorMetrics &m);
nlohmann::json reportJson(const CompareReport &report);

}  // namespace pf::client
