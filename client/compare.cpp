#include "compare.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "compare_report.h"
#include "core/error.h"
#include "embedded_farm.h"
#include "farm_client.h"
#include "farm_commands.h"
#include "farm_job.h"
#include "image/bitmap.h"
#include "image/metrics.h"
#include "integrators/integrator.h"
#include "reference_render.h"
#include "report_html.h"
#include "report_images.h"

namespace pf::client {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

struct CompareCommand::Args {
    std::string scene, reference, output, cacheDir;
    std::vector<std::string> integrators, defines, params;
    double time = 0;
    int repeat = 1, snapshots = 8, threads = 0;
    int64_t referenceSpp = 1024;
    uint64_t seed = 0;
    bool strict = false;
    MetricOptions metrics;
    FarmConnection farm;
    CLI::App *cmd = nullptr;
};

CompareCommand::CompareCommand(CLI::App &app) : a_(std::make_unique<Args>()) {
    Args &a = *a_;
    a.cmd = app.add_subcommand("compare", "Equal-time comparison of integrators on a farm, with an HTML report");
    CLI::App &c = *a.cmd;
    c.add_option("scene", a.scene, "Scene file (Mitsuba 0.5/0.6 XML)")->required();
    c.add_option("--integrators", a.integrators, "Integrators to compare, comma-separated (e.g. path,bdpt)")
        ->required()
        ->delimiter(',')
        ->allow_extra_args(false);
    c.add_option("--time", a.time, "Wall-time budget of every run, in seconds")->required()->check(CLI::PositiveNumber);
    c.add_option("--repeat", a.repeat, "Repetitions of every integrator (seeds seed, seed+1, ...)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    CLI::Option *ref = c.add_option("--reference", a.reference, "Reference EXR (default: render one with BDPT)");
    c.add_option("--reference-spp", a.referenceSpp,
                 "Samples per pixel of the BDPT reference rendered when none is given")
        ->check(CLI::PositiveNumber)
        ->capture_default_str()
        ->excludes(ref);
    c.add_option("--cache-dir", a.cacheDir, "Cache of rendered references (default: ~/.cache/pathfarm/references)");
    c.add_option("-o,--output", a.output, "Output directory: report.json, index.html, EXRs and PNGs")->required();
    c.add_option("--snapshots", a.snapshots, "Snapshots of the running image per run, for the convergence plot")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    c.add_option("--seed", a.seed, "Seed of the first repetition");
    c.add_option("-D", a.defines, "Scene parameter: -D name=value sets $name");
    c.add_option("-P,--param", a.params, "Integrator parameter of every run: -P name=value");
    c.add_flag("--strict", a.strict, "A parameter that its plugin does not use refuses the runs (else a warning)");
    c.add_option("--trim", a.metrics.trimFraction, "Discard this fraction of the highest per-pixel errors (e.g. 0.001)")
        ->check(CLI::Range(0.0, 0.5));
    c.add_option("--epsilon", a.metrics.epsilon, "Epsilon in the denominators of relMSE, MAPE, SMAPE")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    c.add_option("--master", a.farm.master, "Master address host:port (default: an embedded farm on this machine)");
    c.add_option("--token-file", a.farm.tokenFile, "With --master: client token file (default: $PATHFARM_TOKEN)");
    c.add_option("--tls-ca", a.farm.tls.ca, "With --master: PEM CA to connect with TLS");
    c.add_option("--tls-cert", a.farm.tls.cert, "With --master: PEM client certificate (mTLS)");
    c.add_option("--tls-key", a.farm.tls.key, "With --master: PEM private key of --tls-cert");
    // The embedded farm's connection never reconnects: its master does not restart.
    addReconnectOption(c, a.farm.reconnectSeconds);
    c.add_option("--threads", a.threads, "Render threads of the embedded farm's worker (default: all cores)")
        ->check(CLI::PositiveNumber);
}

CompareCommand::~CompareCommand() = default;

namespace {

// Snapshot times spread evenly in log time over [T/32, T): evenly spaced points on the log-log plot.
std::vector<double> snapshotTimes(double budget, int count) {
    std::vector<double> t;
    for (int k = 0; k < count; ++k) t.push_back(budget * std::pow(32.0, static_cast<double>(k - count) / count));
    return t;
}

void checkIntegrators(const std::vector<std::string> &requested) {
    std::vector<std::string> known;
    std::stringstream names(integratorNames());
    for (std::string n; std::getline(names >> std::ws, n, ',');) known.push_back(n);
    if (requested.empty()) throw SceneError("--integrators: give at least one integrator");
    for (const std::string &r : requested)
        if (std::find(known.begin(), known.end(), r) == known.end())
            throw SceneError("--integrators: unknown integrator '" + r + "' (available: " + integratorNames() + ")");
}

std::vector<WorkerSummary> listWorkers(v1::ClientService::Stub &stub, const FarmConnection &farm) {
    v1::ListWorkersReply reply;
    check(stub.ListWorkers(farm.context().get(), v1::ListWorkersRequest(), &reply), "listing workers");
    std::vector<WorkerSummary> out;
    for (const v1::WorkerInfo &w : reply.workers())
        if (w.state() != v1::WORKER_LOST) out.push_back({w.name(), w.threads(), w.cores()});
    return out;
}

// The bytes of a fetched EXR as an image (through a file: the EXR reader reads files).
Bitmap decode(const FetchedImage &image, const fs::path &scratch) {
    writeBytes(scratch.string(), image.exr);
    Bitmap b = readEXR(scratch.string());
    fs::remove(scratch);
    return b;
}

// The comparison itself, on a connected farm.
class Comparison {
public:
    Comparison(const NameValues &defines, const NameValues &params, bool strict, const FarmConnection &farm,
               v1::ClientService::Stub &stub, const fs::path &dir, CompareReport &report)
        : defines_(defines), params_(params), strict_(strict), farm_(farm), stub_(stub), dir_(dir), r_(report) {}

    void run(const std::string &referenceFile, const Bitmap &reference) {
        referenceFile_ = referenceFile;
        reference_ = &reference;
        r_.width = reference.width;
        r_.height = reference.height;
        for (int rep = 0; rep < r_.repeat; ++rep)
            for (const std::string &integrator : r_.integrators) runOne(integrator, rep);
        writeImages();
    }

private:
    ErrorMetrics measure(const Bitmap &image) const {
        try {
            return computeMetrics(image, *reference_, r_.metricOptions);
        } catch (const MetricError &e) {
            throw SceneError(referenceFile_ + ": cannot compare with the rendered image: " + e.what());
        }
    }

    void runOne(const std::string &integrator, int rep) {
        RunResult run;
        run.integrator = integrator;
        run.repetition = rep;
        run.seed = r_.seed + static_cast<uint64_t>(rep);
        v1::JobSpec spec;
        spec.set_bundle_hash(r_.bundleHash);
        spec.set_integrator(integrator);
        setParams(*spec.mutable_params(), params_);
        setParams(*spec.mutable_defines(), defines_);
        spec.mutable_budget()->set_time_seconds(r_.timeBudget);
        spec.set_seed(run.seed);
        spec.set_label("compare " + integrator + " #" + std::to_string(rep));
        spec.set_strict(strict_);
        JobObserver observer;
        observer.snapshotTimes = r_.snapshotTimes;
        observer.submitted = [&](const v1::Job &job) {
            // Every run loads the same scene, so its warnings are shown once.
            if (!warned_) printWarnings(job);
            warned_ = true;
            if (job.width() != r_.width || job.height() != r_.height)
                throw SceneError(referenceFile_ + ": the reference is " + std::to_string(r_.width) + "x" +
                                 std::to_string(r_.height) + " but the scene renders " + std::to_string(job.width()) +
                                 "x" + std::to_string(job.height()));
        };
        observer.snapshot = [&](const JobSnapshot &s) {
            const Bitmap img = decode(s.image, dir_ / ".snapshot.exr");
            run.snapshots.push_back({s.seconds, s.image.info.samples_per_pixel(), measure(img)});
        };
        const FinishedJob done = runJob(stub_, farm_, spec, observer);
        const std::string stem = integrator + "-" + std::to_string(rep);
        run.exr = stem + ".exr";
        run.png = stem + ".png";
        run.errorPng = stem + "-error.png";
        writeBytes((dir_ / run.exr).string(), done.image.exr);
        const Bitmap image = readEXR((dir_ / run.exr).string());
        run.job = done.job.id();
        run.spp = done.job.samples_per_pixel();
        run.tasks = done.job.tasks().merged();
        run.renderSeconds = done.job.render_seconds();
        run.sceneLoadSeconds = done.job.scene_load_seconds();
        run.workerSceneLoadSeconds = done.job.worker_scene_load_seconds();
        run.metrics = measure(image);
        run.efficiency = efficiency(run.metrics.relMse, run.renderSeconds);
        std::fprintf(stderr, "compare: %-8s #%d: job %lld, %lld spp in %.2f s, relMSE %.4g, %zu snapshots\n",
                     integrator.c_str(), rep, static_cast<long long>(run.job), static_cast<long long>(run.spp),
                     run.renderSeconds, run.metrics.relMse, run.snapshots.size());
        r_.runs.push_back(std::move(run));
    }

    // PNGs with one exposure, relMSE error maps on one scale, and crops of the regions of largest error.
    void writeImages() {
        r_.exposure = autoExposure(*reference_);
        r_.reference.png = "reference.png";
        writePNG((dir_ / r_.reference.png).string(), *reference_, r_.exposure);
        std::vector<ErrorMap> maps;
        std::vector<Bitmap> firstImages;
        for (const RunResult &run : r_.runs) {
            const Bitmap image = readEXR((dir_ / run.exr).string());
            writePNG((dir_ / run.png).string(), image, r_.exposure);
            maps.push_back(errorMap(image, *reference_, Metric::RelMSE, r_.metricOptions.epsilon));
            if (run.repetition == 0) firstImages.push_back(image);
        }
        // The scale: the 99th percentile of every map's per-pixel relMSE, so that a few fireflies do not
        // turn every other pixel black.
        ErrorMap all{static_cast<int>(maps.size()) * r_.width, r_.height, {}};
        for (const ErrorMap &m : maps) all.values.insert(all.values.end(), m.values.begin(), m.values.end());
        r_.errorMapMax = quantile(all, 0.99);
        for (size_t i = 0; i < r_.runs.size(); ++i)
            writePNG((dir_ / r_.runs[i].errorPng).string(), falseColour(maps[i], r_.errorMapMax), 0.0);

        std::vector<ErrorMap> firstMaps;
        for (size_t i = 0; i < r_.runs.size(); ++i)
            if (r_.runs[i].repetition == 0) firstMaps.push_back(maps[i]);
        constexpr int kCrops = 3;
        int index = 1;
        for (const Region &region : regionsOfLargestError(firstMaps, kCrops)) {
            CropRegion c{region.x, region.y, region.size, {}};
            const auto save = [&](const std::string &name, const Bitmap &image) {
                const std::string png = "crop" + std::to_string(index) + "-" + name + ".png";
                writePNG((dir_ / png).string(), crop(image, region), r_.exposure);
                c.pngs.emplace_back(name, png);
            };
            save("reference", *reference_);
            for (size_t i = 0; i < r_.integrators.size(); ++i) save(r_.integrators[i], firstImages[i]);
            r_.crops.push_back(std::move(c));
            ++index;
        }
    }

    const NameValues &defines_, &params_;
    bool strict_, warned_ = false;
    const FarmConnection &farm_;
    v1::ClientService::Stub &stub_;
    fs::path dir_;
    CompareReport &r_;
    std::string referenceFile_;
    const Bitmap *reference_ = nullptr;
};

void writeText(const fs::path &path, const std::string &text) {
    std::ofstream f(path, std::ios::binary);
    f << text;
    if (!f) throw std::runtime_error("cannot write " + path.string());
}

void printSummary(const CompareReport &r) {
    std::printf("%-10s %5s %10s %10s %12s %12s %12s\n", "ALGORITHM", "RUNS", "SPP", "SECONDS", "RELMSE", "+-",
                "EFFICIENCY");
    for (const IntegratorSummary &s : summarize(r))
        std::printf("%-10s %5d %10.1f %10.2f %12.4g %12.2g %12.4g\n", s.integrator.c_str(), s.runs, s.get("spp").mean,
                    s.get("renderSeconds").mean, s.get("relmse").mean, s.get("relmse").stddev,
                    s.get("efficiency").mean);
}

}  // namespace

int CompareCommand::run() {
    const Args &a = *a_;
    if (!*a.cmd) return -1;
    checkIntegrators(a.integrators);
    const NameValues defines = parseNameValues(a.defines, "-D"), params = parseNameValues(a.params, "-P");
    Bitmap reference;
    if (!a.reference.empty()) reference = readEXR(a.reference);  // SceneError naming the file
    const SceneBundle bundle = makeSceneBundle(a.scene, defines);
    const fs::path dir(a.output);
    fs::create_directories(dir);

    std::unique_ptr<EmbeddedFarm> embedded;
    FarmConnection farm = a.farm;
    if (farm.master.empty()) {
        embedded = std::make_unique<EmbeddedFarm>(a.threads);
        farm = embedded->connection();
    }
    CompareReport r;
    r.scene = a.scene;
    r.bundleHash = bundle.hash;
    r.master = farm.master;
    r.embeddedFarm = embedded != nullptr;
    r.integrators = a.integrators;
    r.defines = defines;
    r.params = params;
    r.timeBudget = a.time;
    r.repeat = a.repeat;
    r.seed = a.seed;
    r.snapshotTimes = snapshotTimes(a.time, a.snapshots);
    r.metricOptions = a.metrics;
    try {
        const auto stub = v1::ClientService::NewStub(farm.channel());
        uploadBundle(*stub, farm, bundle);
        r.workers = listWorkers(*stub, farm);
        std::string referenceFile = a.reference;
        if (a.reference.empty()) {
            // Its own seed stream, far from the runs' seeds, so no run shares random numbers with it.
            const ReferenceRequest req{a.cacheDir, a.referenceSpp, a.seed + 0x5eed0000u, defines, params, a.strict};
            reference = obtainReference(*stub, farm, bundle, req, r.reference);
            referenceFile = r.reference.cacheFile;
        } else {
            r.reference.source = "file";
        }
        r.reference.exr = "reference.exr";
        writeEXR((dir / r.reference.exr).string(), reference);
        Comparison(defines, params, a.strict, farm, *stub, dir, r).run(referenceFile, reference);
    } catch (const CallError &e) {
        if (e.code == grpc::StatusCode::INVALID_ARGUMENT) throw SceneError(e.what());
        throw;
    }
    writeText(dir / "report.json", reportJson(r).dump(2) + "\n");
    writeText(dir / "index.html", reportHtml(r));
    printSummary(r);
    std::printf("report: %s\n", (dir / "index.html").string().c_str());
    return 0;
}

}  // namespace pf::client
