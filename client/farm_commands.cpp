#include "farm_commands.h"

#include <google/protobuf/util/json_util.h>

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "farm/bundle.h"
#include "farm/convert.h"
#include "farm/job_setup.h"
#include "farm/rpc.h"
#include "farm_client.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "pathfarm/v1/client.grpc.pb.h"
#include "render/image_task.h"

namespace pf::client {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

// A Markov-chain job's budget is in mutations per pixel, an image job's in samples per pixel.
std::string progressLine(const v1::Job &j) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "job %" PRId64 " %s %5.1f%%: %" PRId64 " %s, %" PRId64 "/%s tasks merged, %" PRId64 " leased, %.1f s",
                  j.id(), farm::stateName(j.state()).c_str(), 100.0 * j.progress(), j.samples_per_pixel(),
                  j.has_chain() ? "mutations/pixel" : "spp", j.tasks().merged(),
                  j.tasks().total() > 0 ? std::to_string(j.tasks().total()).c_str() : "?", j.tasks().leased(),
                  j.render_seconds());
    return line;
}

}  // namespace

struct FarmCommands::Args : FarmConnection {
    // submit
    std::string scene, integrator, output, label;
    int64_t spp = 0;
    double time = 0;
    uint64_t seed = 0;
    int priority = 0;
    std::vector<std::string> params, defines;
    bool wait = false, strict = false;
    // the other commands
    int64_t job = 0;
    bool all = false;

    CLI::App *submit, *status, *watch, *fetch, *cancel, *workers, *health;
};

FarmCommands::FarmCommands(CLI::App &app) : a_(std::make_unique<Args>()) {
    Args &a = *a_;
    const char *env = std::getenv("PATHFARM_MASTER");
    a.master = env && *env ? env : "127.0.0.1:7700";
    auto common = [&](CLI::App *cmd) {
        cmd->add_option("--master", a.master, "Master address host:port (default: $PATHFARM_MASTER or 127.0.0.1:7700)");
        cmd->add_option("--token-file", a.tokenFile, "File holding the client token (default: $PATHFARM_TOKEN)");
        cmd->add_option("--tls-ca", a.tls.ca, "PEM CA: connect with TLS, trusting these roots");
        cmd->add_option("--tls-cert", a.tls.cert, "PEM client certificate (mTLS)");
        cmd->add_option("--tls-key", a.tls.key, "PEM private key of --tls-cert");
        return cmd;
    };
    a.submit = common(app.add_subcommand("submit", "Upload a scene and submit a job to the farm"));
    a.submit->add_option("scene", a.scene, "Scene file (Mitsuba 0.5/0.6 XML)")->required();
    a.submit->add_option("-i,--integrator", a.integrator, "Integrator (default: the scene's)");
    a.submit->add_option("--spp", a.spp, "Samples per pixel (default: the scene's sampleCount)")
        ->check(CLI::PositiveNumber);
    a.submit->add_option("--time", a.time, "Wall-time budget in seconds, spent in whole tasks")
        ->check(CLI::PositiveNumber);
    a.submit->add_option("--seed", a.seed, "Seed of every random stream");
    a.submit->add_option("-D", a.defines, "Scene parameter: -D name=value sets $name");
    a.submit->add_option("-P,--param", a.params, "Integrator parameter: -P name=value");
    a.submit->add_option("--priority", a.priority, "Higher runs first (default 0)");
    a.submit->add_option("--label", a.label, "Text shown in listings");
    a.submit->add_flag("--strict", a.strict,
                       "A parameter that its plugin does not use refuses the job (else a warning)");
    a.submit->add_flag("--wait", a.wait, "Wait for the job, printing progress, then fetch its image");
    a.submit->add_option("-o,--output", a.output, "With --wait: output EXR (default: named after the scene)");
    addReconnectOption(*a.submit, a.reconnectSeconds);

    a.status = common(app.add_subcommand("status", "List jobs, or show one"));
    a.status->add_option("job", a.job, "Job id");
    a.watch = common(app.add_subcommand("watch", "Follow a job until it ends"));
    a.watch->add_option("job", a.job, "Job id")->required();
    addReconnectOption(*a.watch, a.reconnectSeconds);
    a.fetch = common(app.add_subcommand("fetch", "Download a job's image (the running image if unfinished)"));
    a.fetch->add_option("job", a.job, "Job id")->required();
    a.fetch->add_option("-o,--output", a.output, "Output EXR")->required();
    addReconnectOption(*a.fetch, a.reconnectSeconds);
    a.cancel = common(app.add_subcommand("cancel", "Cancel a job"));
    a.cancel->add_option("job", a.job, "Job id")->required();
    a.workers = common(app.add_subcommand("workers", "List the farm's workers"));
    a.workers->add_flag("--all", a.all, "Include workers that are gone");
    a.health = common(app.add_subcommand("health", "Check the master's gRPC health service"));
}

FarmCommands::~FarmCommands() = default;

namespace {

// Follows a job through WatchJob, printing a line per change; returns the job as it ended. A watch cut
// off by the master's restart is opened again: it starts with the job's current state.
v1::Job follow(v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id) {
    v1::WatchJobRequest req;
    req.set_id(id);
    Reconnector reconnect(farm, "watching job " + std::to_string(id));
    v1::Job job;
    for (;;) {
        const auto ctx = farm.context(0);
        auto reader = stub.WatchJob(ctx.get(), req);
        while (reader->Read(&job)) {
            reconnect.reached();
            std::fprintf(stderr, "%s\n", progressLine(job).c_str());
        }
        grpc::Status s = reader->Finish();
        // The master ends a watch early only when it goes away (a write to a closing server fails).
        if (s.ok() && !jobEnded(job)) s = grpc::Status(grpc::StatusCode::UNAVAILABLE, "the watch ended before the job");
        if (s.ok()) return job;
        reconnect.failed(s);
    }
}

void fetchImage(v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id, const std::string &output) {
    const FetchedImage image = client::fetchImage(stub, farm, id);
    writeBytes(output, image.exr);
    const std::string partial = partialPassSummary(image.info.partial_pass_share());
    std::printf("job %" PRId64 ": %s image, %" PRId64 " spp%s -> %s\n", id, image.info.final() ? "final" : "running",
                image.info.samples_per_pixel(), partial.c_str(), output.c_str());
}

}  // namespace

CLI::Option *addReconnectOption(CLI::App &cmd, int &seconds) {
    seconds = 120;
    return cmd
        .add_option("--reconnect-timeout", seconds,
                    "Seconds to keep reconnecting to a master that restarts or drops the connection (0: fail at once)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
}

std::string defaultOutput(const std::string &scenePath) {
    const fs::path p(scenePath);
    const std::string stem =
        p.stem() == "scene" && p.has_parent_path() ? p.parent_path().filename().string() : p.stem().string();
    return stem + ".exr";
}

int FarmCommands::run() {
    const Args &a = *a_;
    const auto ctx = [&](int timeout = 60) { return a.context(timeout); };
    try {
        if (*a.health) {
            const auto stub = grpc::health::v1::Health::NewStub(a.channel());
            grpc::ClientContext c;
            c.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
            grpc::health::v1::HealthCheckResponse reply;
            check(stub->Check(&c, grpc::health::v1::HealthCheckRequest(), &reply), "health of " + a.master);
            const bool serving = reply.status() == grpc::health::v1::HealthCheckResponse::SERVING;
            std::printf("%s: %s\n", a.master.c_str(), serving ? "SERVING" : "NOT_SERVING");
            return serving ? 0 : 1;
        }
        if (!*a.submit && !*a.status && !*a.watch && !*a.fetch && !*a.cancel && !*a.workers) return -1;
        const auto stub = v1::ClientService::NewStub(a.channel());

        if (*a.submit) {
            const NameValues defines = parseNameValues(a.defines, "-D"), params = parseNameValues(a.params, "-P");
            const SceneBundle bundle = makeSceneBundle(a.scene, defines);
            uploadBundle(*stub, a, bundle);
            v1::SubmitJobRequest req;
            v1::JobSpec &spec = *req.mutable_spec();
            spec.set_bundle_hash(bundle.hash);
            spec.set_integrator(a.integrator);
            setParams(*spec.mutable_params(), params);
            setParams(*spec.mutable_defines(), defines);
            if (a.time > 0) {
                spec.mutable_budget()->set_time_seconds(a.time);
            } else if (a.spp > 0) {
                spec.mutable_budget()->set_spp(a.spp);
            }
            spec.set_seed(a.seed);
            spec.set_priority(a.priority);
            spec.set_label(a.label.empty() ? bundle.sceneFile : a.label);
            spec.set_strict(a.strict);
            v1::Job job;
            check(stub->SubmitJob(ctx().get(), req, &job), "submitting " + a.scene);
            printWarnings(job);
            std::printf("job %" PRId64 " submitted: %s, %dx%d, %s\n", job.id(), job.scene_file().c_str(), job.width(),
                        job.height(), job.integrator().c_str());
            std::fflush(stdout);
            if (!a.wait) return 0;
            const v1::Job last = follow(*stub, a, job.id());
            if (last.state() != v1::JOB_DONE) {
                std::fprintf(stderr, "error: job %" PRId64 " %s%s%s\n", last.id(),
                             farm::stateName(last.state()).c_str(), last.error().empty() ? "" : ": ",
                             last.error().c_str());
                return 1;
            }
            fetchImage(*stub, a, job.id(), a.output.empty() ? defaultOutput(a.scene) : a.output);
            return 0;
        }
        if (*a.status) {
            if (a.job > 0) {
                v1::GetJobRequest req;
                req.set_id(a.job);
                v1::Job job;
                check(stub->GetJob(ctx().get(), req, &job), "job " + std::to_string(a.job));
                google::protobuf::util::JsonPrintOptions opts;
                opts.add_whitespace = true;
                std::string json;
                (void)google::protobuf::util::MessageToJsonString(job, &json, opts);
                std::printf("%s", json.c_str());
                return 0;
            }
            v1::ListJobsReply reply;
            check(stub->ListJobs(ctx().get(), v1::ListJobsRequest(), &reply), "listing jobs");
            std::printf("%6s  %-9s %6s %8s  %-8s %11s %9s  %s\n", "JOB", "STATE", "DONE", "SPP", "ALGO", "SIZE",
                        "SECONDS", "LABEL");
            for (const v1::Job &j : reply.jobs()) {
                const std::string size = std::to_string(j.width()) + "x" + std::to_string(j.height());
                std::printf("%6" PRId64 "  %-9s %5.1f%% %8" PRId64 "  %-8s %11s %9.1f  %s\n", j.id(),
                            farm::stateName(j.state()).c_str(), 100.0 * j.progress(), j.samples_per_pixel(),
                            j.integrator().c_str(), size.c_str(), j.render_seconds(), j.spec().label().c_str());
            }
            return 0;
        }
        if (*a.watch) {
            const v1::Job last = follow(*stub, a, a.job);
            return last.state() == v1::JOB_DONE ? 0 : 1;
        }
        if (*a.fetch) {
            fetchImage(*stub, a, a.job, a.output);
            return 0;
        }
        if (*a.cancel) {
            v1::CancelJobRequest req;
            req.set_id(a.job);
            v1::Job job;
            check(stub->CancelJob(ctx().get(), req, &job), "cancelling job " + std::to_string(a.job));
            std::printf("%s\n", progressLine(job).c_str());
            return 0;
        }
        v1::ListWorkersReply reply;
        check(stub->ListWorkers(ctx().get(), v1::ListWorkersRequest(), &reply), "listing workers");
        std::printf("%-16s %-9s %7s %6s %12s %7s  %-8s %s\n", "WORKER", "STATE", "THREADS", "TASKS", "SAMPLES/S",
                    "LEASES", "VERSION", "NAME");
        for (const v1::WorkerInfo &w : reply.workers()) {
            if (w.state() == v1::WORKER_LOST && !a.all) continue;
            std::printf("%-16s %-9s %7d %6" PRId64 " %12.3g %7d  %-8s %s\n", w.id().c_str(),
                        farm::stateName(w.state()).c_str(), w.threads(), w.tasks_completed(), w.samples_per_second(),
                        w.attempt_ids_size(), w.version().c_str(), w.name().c_str());
        }
        return 0;
    } catch (const CallError &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return e.code == grpc::StatusCode::INVALID_ARGUMENT ? kExitBadInput : 1;
    } catch (const SceneError &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return kExitBadInput;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
}

}  // namespace pf::client
