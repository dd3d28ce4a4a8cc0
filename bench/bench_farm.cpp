// Farm overhead and master cost per task, with real processes on loopback. Prints figures; never
// passes or fails on time.
//
//   bench_farm [SCENE] [--res N] [--spp N] [--fake-workers N] [--fake-tasks N] [--fake-res N] [--fake-only]
//              [--fake-batch N|auto[,...]] [--task-seconds S]
//   bench_farm [SCENE] --chain NAME [--chain-tasks K] [-P name=value ...] [--chain-farm S [--fake-workers N]
//              [--fake-batch N|auto[,...]]]
//   (default: scenes/cornell-box/scene.xml at 256x256, 64 spp; 32 fake workers, 400 tasks at --res,
//   batches of 1)
//
// 1. The same job rendered embedded (`pathfarm render --threads 2`) and by a farm of one local worker
//    with 2 threads: samples/s of each and their ratio (farm time runs from the first lease to the
//    last merge, so it includes the worker fetching the bundle and loading the scene).
// 2. What a task costs the master: CPU seconds of the master process per task over the whole job
//    (gRPC, validation, storing, merging, checkpoints, leases), the decode + merge time of one result
//    measured in-process, and the bytes of a result on the wire.
// 3. From these, how many 8-core workers one master can keep busy at this task size.
// 4. The master with many workers: a fresh master, and N fake workers in this process, each
//    with its own connection, that register, lease, heartbeat and return results through the real gRPC
//    API as fast as the master hands out tasks. A result is a real encoded film block of the task's
//    sample count (rendered once per count, so the image is not the job's: this part measures cost,
//    part 1 checks bits). Printed: the master's CPU per idle worker and second (no job), then under a
//    saturating task rate its CPU per task, the tasks per second it sustains, the bytes per task on the
//    wire, and the 8-core workers that implies (their task time from part 1). With --fake-batch N the
//    fake workers lease N tasks at once and return them as one result (pathfarm-worker --batch N; auto
//    leaves the size to the master, as pathfarm-worker does by default); a list of sizes runs part 4 once
//    per size, each with a fresh master. --task-seconds S: also the 8-core
//    workers one master keeps busy at tasks of S seconds (e.g. part 1's smallest task, under --fake-only).
// 5. --chain NAME [--chain-tasks K] [-P name=value ...] (instead of 1-4): what a chain task's result costs, at
//    the scene's own resolution, with its film as tiles (now, image/splat_tiles.h) and as the dense block of
//    the whole crop window that chain tasks returned before (the same deposits merged into one): the film's
//    memory, bytes on the wire, the worker's encode time and the master's decode + merge time per result,
//    through the real codec and merge (decodeChainResult into a fresh block, mergeChainResult into the
//    job's chains). The tasks are the first K (default 8, a pass of erpt/mept) of a time-budgeted render of
//    integrator NAME with job seed 1, run on 2 threads; both merged films must come out bitwise equal. Then the
//    same K results as one batch (pathfarm-worker --batch K): its bytes, the worker's summing and encoding and
//    the master's decode + merge.
// 6. --chain-farm S (after 5): a chain job of integrator NAME under --time S at the scene's own size, on a fresh
//    master with N fake workers (part 4's) that return part 5's results at once (a batch of n chain tasks: the
//    sum of the first min(n, K)), once per --fake-batch size: tasks per result (all, and chain tasks per chain
//    result), the master's CPU per chain task (its whole CPU, seeding and direct tasks included, over the chain
//    tasks) and the 8-core workers one master core keeps busy at part 5's mean chain task time.
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/harness.h"
#include "farm/hash.h"
#include "farm/job_setup.h"
#include "farm/rpc.h"
#include "image/bitmap.h"
#include "render/chain_job.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace fs = std::filesystem;
using namespace pf;
using namespace std::chrono_literals;

namespace {

// utime + stime of a process, in seconds.
double cpuSeconds(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));
    std::string skip;
    for (int i = 3; i < 14; ++i) fields >> skip;  // state .. cmajflt
    double utime = 0, stime = 0;
    fields >> utime >> stime;
    return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// A copy of the scene's directory with the film resized (the bundle is the copy).
std::string resizedCopy(const std::string &scene, int res, const std::string &dir) {
    const fs::path src = fs::absolute(scene);
    fs::create_directories(dir);
    fs::copy(src.parent_path(), dir, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
    const fs::path copy = fs::path(dir) / src.filename();
    std::string xml = farm::readFile(copy.string());
    xml = std::regex_replace(xml, std::regex(R"re((name="(width|height)"\s+value=")\d+")re"),
                             "$01" + std::to_string(res) + "\"");
    std::ofstream(copy) << xml;
    return copy.string();
}

double metadataSeconds(const std::string &exr) { return std::stod(readEXR(exr).metadata.at("pathfarm.renderSeconds")); }

namespace v1 = pathfarm::v1;

// An encoded film block per task sample count of a job of `spp` samples per pixel. Blocks of more
// than 16 samples are rendered with 16 (the master does not look at the values, and the size of a
// compressed block hardly depends on the sample count), so that the setup takes seconds.
std::map<int64_t, std::string> resultsBySampleCount(const std::string &scene, int64_t spp) {
    auto loaded = loadScene(scene);
    const auto integrator = makeIntegrator(*loaded, "", {});
    std::map<int64_t, std::string> out;
    const int64_t pixels = filmPixels(loaded->sensor().film());
    for (int64_t first = 0; first < spp; first += imageTaskSize(spp, first, pixels)) {
        const int64_t count = imageTaskSize(spp, first, pixels);
        if (!out.count(count))
            out[count] = farm::encodeBlock(runImageTask(*loaded, dynamic_cast<const SamplingIntegrator &>(*integrator),
                                                        1, ImageTask{0, std::min<int64_t>(count, 16)}, 2)
                                               .block);
    }
    return out;
}

// What a fake worker returns for a lease (its task and the batch after it): the payload, and TaskStats.samples.
using PayloadFor = std::function<std::pair<const std::string *, uint64_t>(const v1::LeaseReply &)>;

// A worker that returns precomputed results over its own connection, as fast as the master leases.
class FakeWorker {
public:
    FakeWorker(const std::string &address, const std::string &token, PayloadFor payloadFor, int batch)
        : token_(token), payloadFor_(std::move(payloadFor)), batch_(batch) {
        grpc::ChannelArguments args;
        args.SetMaxReceiveMessageSize(64 << 20);
        args.SetMaxSendMessageSize(64 << 20);
        // A connection of its own, as a worker on another host has (channels otherwise share one).
        args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
        stub_ =
            v1::WorkerService::NewStub(grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args));
        v1::RegisterRequest req;
        req.set_name("fake");
        v1::RegisterReply reply;
        check(stub_->Register(context().get(), req, &reply), "Register");
        id_ = reply.worker_id();
        heartbeat_ = std::chrono::milliseconds(reply.heartbeat_ms());
        chunk_ = static_cast<size_t>(std::max<uint64_t>(reply.max_message_bytes(), 8192) - 4096);
        bytes_ += req.ByteSizeLong() + reply.ByteSizeLong();
    }

    // Leases and completes tasks until the master has none left and `done` is set.
    void run(const std::atomic<bool> &done) {
        auto lastBeat = std::chrono::steady_clock::now();
        for (;;) {
            v1::LeaseRequest req;
            req.set_worker_id(id_);
            req.set_wait_ms(2000);  // as pathfarm-worker long-polls
            req.set_max_tasks(batch_);
            v1::LeaseReply reply;
            check(stub_->LeaseTask(context().get(), req, &reply), "LeaseTask");
            bytes_ += req.ByteSizeLong() + reply.ByteSizeLong();
            if (reply.has_task()) {
                complete(reply);
                tasks_ += 1 + reply.more_size();
                ++returned_;
            } else if (done) {
                return;
            }
            if (std::chrono::steady_clock::now() - lastBeat >= heartbeat_) {
                v1::HeartbeatRequest beat;
                beat.set_worker_id(id_);
                v1::HeartbeatReply beatReply;
                check(stub_->Heartbeat(context().get(), beat, &beatReply), "Heartbeat");
                bytes_ += beat.ByteSizeLong() + beatReply.ByteSizeLong();
                lastBeat = std::chrono::steady_clock::now();
            }
        }
    }
    int64_t tasks() const { return tasks_; }
    int64_t returned() const { return returned_; }
    uint64_t bytes() const { return bytes_; }

private:
    // One result for the leased tasks.
    void complete(const v1::LeaseReply &lease) {
        const v1::TaskSpec &task = lease.task();
        const auto [payloadPtr, samples] = payloadFor_(lease);
        const std::string &payload = *payloadPtr;
        v1::CompleteReply reply;
        const auto ctx = context();
        auto writer = stub_->CompleteTask(ctx.get(), &reply);
        v1::ResultChunk header;
        v1::ResultHeader *h = header.mutable_header();
        h->set_worker_id(id_);
        h->set_attempt_id(task.attempt_id());
        for (const v1::TaskSpec &t : lease.more()) h->add_batch_attempt_ids(t.attempt_id());
        h->mutable_stats()->set_samples(samples);
        h->mutable_stats()->set_seconds(1e-3);
        h->set_payload_size(payload.size());
        h->set_payload_hash(farm::hashHex64(payload));
        bool written = writer->Write(header);
        bytes_ += header.ByteSizeLong();
        // In messages the master accepts, as pathfarm-worker sends them.
        for (size_t off = 0; written && off < payload.size(); off += chunk_) {
            v1::ResultChunk data;
            data.set_data(payload.substr(off, chunk_));
            written = writer->Write(data);
            bytes_ += data.ByteSizeLong();
        }
        if (!written) std::fprintf(stderr, "fake worker: write failed\n");
        writer->WritesDone();
        check(writer->Finish(), "CompleteTask");
        if (!reply.accepted()) std::fprintf(stderr, "fake worker: result ignored: %s\n", reply.reason().c_str());
        bytes_ += reply.ByteSizeLong();
    }
    std::unique_ptr<grpc::ClientContext> context() const {
        auto ctx = std::make_unique<grpc::ClientContext>();
        farm::setBearer(*ctx, token_);
        ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
        return ctx;
    }
    static void check(const grpc::Status &s, const char *call) {
        if (!s.ok()) throw std::runtime_error(std::string("fake worker: ") + call + ": " + s.error_message());
    }

    std::string token_;
    PayloadFor payloadFor_;
    int batch_;
    std::unique_ptr<v1::WorkerService::Stub> stub_;
    std::string id_;
    std::chrono::milliseconds heartbeat_{3000};
    size_t chunk_ = 4 << 20;  // payload bytes per message
    int64_t tasks_ = 0, returned_ = 0;
    uint64_t bytes_ = 0;
};

// Fake workers on the real API, and what a job costs the master from its submission to its end.
struct Saturated {
    v1::Job job;
    double cpu = 0, wall = 0;  // the master's CPU seconds, and wall seconds
    uint64_t bytes = 0;        // protobuf messages both ways
    int64_t leased = 0, returned = 0;
};

// Starts `workers` fake workers leasing `batch` tasks at a time; `submit` (run once they poll) returns the CLI's
// arguments of the job. Exits the process when the job fails.
Saturated runSaturated(test::farm::Farm &farm, test::farm::Process &master, int workers, int batch,
                       const PayloadFor &payloadFor, const std::function<std::string()> &submit) {
    std::vector<std::unique_ptr<FakeWorker>> fakes;
    for (int i = 0; i < workers; ++i)
        fakes.push_back(std::make_unique<FakeWorker>(farm.address(), farm.workerToken(), payloadFor, batch));
    std::atomic<bool> done{false};
    std::vector<std::thread> threads;
    for (auto &f : fakes)
        threads.emplace_back([&, w = f.get()] {
            try {
                w->run(done);
            } catch (const std::exception &e) {
                std::fprintf(stderr, "%s\n%s\n", e.what(), master.log().c_str());
                std::exit(1);
            }
        });
    const std::string args = submit();
    // The master's CPU from submission (after its validation load of the scene) to the final image.
    const auto [scode, sout] = farm.cli(args);
    const int64_t id = test::farm::jobIdFrom(sout);
    Saturated r;
    const double cpu0 = cpuSeconds(master.pid());
    const auto t0 = std::chrono::steady_clock::now();
    r.job = farm.waitForJob(id, std::chrono::seconds(3600));
    r.cpu = cpuSeconds(master.pid()) - cpu0;
    r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    done = true;
    for (std::thread &t : threads) t.join();
    if (scode != 0 || r.job.state() != v1::JOB_DONE) {
        std::fprintf(stderr, "saturation job failed: %s\n%s\n", sout.c_str(), master.log().c_str());
        std::exit(1);
    }
    for (const auto &f : fakes) {
        r.bytes += f->bytes();
        r.leased += f->tasks();
        r.returned += f->returned();
    }
    return r;
}

// Part 4: the master's cost per task under `workers` fake workers returning `batch` tasks per result;
// with the time an 8-core worker takes per pixel sample (0: unknown), the workers of 8 cores that one
// master keeps busy. `results` is filled on the first call (the rendering takes a while).
void saturate(const std::string &scene, int res, int workers, int64_t tasks, double sampleSeconds8, int batch,
              double taskSeconds, std::map<int64_t, std::string> &results) {
    test::farm::Farm farm("bench-saturate");
    const std::string copy = resizedCopy(scene, res, farm.dir() + "/scene");
    int64_t spp = 0;
    for (int64_t n = 0; n < tasks; ++n)
        spp += imageTaskSize(std::numeric_limits<int64_t>::max(), spp, int64_t{res} * res);
    if (results.empty()) results = resultsBySampleCount(copy, spp);
    test::farm::Process &master = farm.startMaster({"--max-spp", std::to_string(spp)});
    // A batch's result: the first task's block stands for their sum, as the size of a compressed block hardly
    // depends on its sample count.
    const PayloadFor payloadFor = [&, pixels = uint64_t(res) * uint64_t(res)](const v1::LeaseReply &lease) {
        uint64_t samples = static_cast<uint64_t>(lease.task().image().sample_count());
        for (const v1::TaskSpec &t : lease.more()) samples += static_cast<uint64_t>(t.image().sample_count());
        return std::make_pair(&results.at(lease.task().image().sample_count()), samples * pixels);
    };
    const Saturated r = runSaturated(farm, master, workers, batch, payloadFor, [&] {
        // What workers cost the master while there is no work: long-polls and heartbeats.
        const double idleCpu0 = cpuSeconds(master.pid());
        constexpr int kIdleSeconds = 6;
        std::this_thread::sleep_for(std::chrono::seconds(kIdleSeconds));
        const double idlePerWorker = (cpuSeconds(master.pid()) - idleCpu0) / kIdleSeconds / workers;
        std::printf(
            "idle: %d fake workers polling: %.3f ms of master CPU per second per worker (500 workers: %.0f%% of "
            "a core)\n",
            workers, 1e3 * idlePerWorker, 100 * 500 * idlePerWorker);
        return "submit " + copy + " --spp " + std::to_string(spp) + " --seed 1";
    });
    const v1::Job &job = r.job;
    const double cpu = r.cpu, wall = r.wall;
    const uint64_t bytes = r.bytes;
    const int64_t leased = r.leased, returned = r.returned;
    const double n = static_cast<double>(job.tasks().merged());
    std::printf(
        "saturation: %d fake workers, batches of %s (%.1f tasks per result), %lld tasks of %dx%d (%lld spp) "
        "in %.2f s\n",
        workers, batch == farm::kAutoBatch ? "auto" : std::to_string(batch).c_str(),
        static_cast<double>(leased) / static_cast<double>(std::max<int64_t>(1, returned)),
        static_cast<long long>(job.tasks().merged()), res, res, static_cast<long long>(spp), wall);
    std::printf("  master CPU:                %8.3f ms per task\n", 1e3 * cpu / n);
    std::printf("  tasks per second:          %8.1f  (master CPU %.0f%% of one core; the machine may be shared)\n",
                n / wall, 100 * cpu / wall);
    std::printf("  tasks per CPU-second:      %8.1f  (what one master core sustains)\n", n / cpu);
    std::printf("  bytes per task:            %8.0f  (protobuf messages both ways, heartbeats included)\n",
                static_cast<double>(bytes) / n);
    if (taskSeconds > 0)
        std::printf("  8-core workers per master:  %7.0f at tasks of %.3f s; goal >= 500\n", taskSeconds / (cpu / n),
                    taskSeconds);
    if (sampleSeconds8 <= 0) return;
    // This job's tasks are mostly of the largest size (render/image_task.h); a job as short as part 1's
    // has only small ones.
    const double pixels = static_cast<double>(res) * res, cpuPerTask = cpu / n;
    const double meanTask = sampleSeconds8 * pixels * static_cast<double>(spp) / n;
    const double smallest = sampleSeconds8 * pixels * static_cast<double>(imageTaskSize(spp, 0, int64_t{res} * res));
    const double largest = sampleSeconds8 * pixels * static_cast<double>(results.rbegin()->first);
    std::printf(
        "  8-core workers per master:  %7.0f at this job's mean task (%.3f s on 8 cores), %.0f at the\n"
        "                              smallest task (%.3f s), %.0f at the largest (%.3f s); goal >= 500\n",
        meanTask / cpuPerTask, meanTask, smallest / cpuPerTask, smallest, largest / cpuPerTask, largest);
}

// Parts 1-3: prints the master's cost per task over the whole job; returns the time an 8-core worker
// takes per pixel sample (a quarter of the 2-thread farm's).
double realFarm(const std::string &scene, int res, int spp) {
    test::farm::Farm farm("bench");
    const std::string copy = resizedCopy(scene, res, farm.dir() + "/scene");
    const std::string spec = " --spp " + std::to_string(spp) + " --seed 1";
    const double samples = static_cast<double>(res) * res * spp;
    std::printf("scene %s at %dx%d, %d spp, path tracer\n", scene.c_str(), res, res, spp);

    // 1. Embedded and farm, both with 2 threads, each twice (the faster run counts: the machine may be
    //    shared, and the first run warms caches).
    const std::string embedded = farm.dir() + "/embedded.exr", farmed = farm.dir() + "/farm.exr";
    double embeddedSeconds = 1e30, farmSeconds = 1e30, loadSeconds = 0, masterCpu = 0;
    for (int run = 0; run < 2; ++run) {
        const auto [code, out] = farm.cli("render " + copy + " -q --threads 2" + spec + " -o " + embedded);
        if (code != 0) {
            std::fprintf(stderr, "embedded render failed: %s\n", out.c_str());
            std::exit(1);
        }
        embeddedSeconds = std::min(embeddedSeconds, metadataSeconds(embedded));
    }
    test::farm::Process &master = farm.startMaster();
    farm.startWorker(2);
    int64_t id = 0;
    for (int run = 0; run < 2; ++run) {
        // The master's CPU from submission (after its validation load of the scene) to the final image.
        const auto [scode, sout] = farm.cli("submit " + copy + spec);
        id = test::farm::jobIdFrom(sout);
        const double cpu0 = cpuSeconds(master.pid());
        const auto [wcode, wout] = farm.cli("watch " + std::to_string(id));
        masterCpu = cpuSeconds(master.pid()) - cpu0;
        const auto [fcode, fout] = farm.cli("fetch " + std::to_string(id) + " -o " + farmed);
        if (scode != 0 || wcode != 0 || fcode != 0) {
            std::fprintf(stderr, "farm job failed: %s%s%s\n%s\n", sout.c_str(), wout.c_str(), fout.c_str(),
                         master.log().c_str());
            std::exit(1);
        }
        if (metadataSeconds(farmed) < farmSeconds) {
            farmSeconds = metadataSeconds(farmed);
            loadSeconds = std::stod(readEXR(farmed).metadata.at("pathfarm.workerSceneLoadSeconds"));
        }
    }
    std::printf("embedded (2 threads):        %8.3f s  %10.4g samples/s\n", embeddedSeconds, samples / embeddedSeconds);
    std::printf("farm (1 worker, 2 threads):  %8.3f s  %10.4g samples/s  (incl. %.3f s bundle fetch + scene load)\n",
                farmSeconds, samples / farmSeconds, loadSeconds);
    std::printf("farm overhead ratio:         %8.3f  (farm samples/s over embedded; goal >= 0.95)\n",
                embeddedSeconds / farmSeconds);
    std::printf("  scene load excluded:       %8.3f  (as the embedded figure excludes it)\n",
                embeddedSeconds / (farmSeconds - loadSeconds));
    std::printf("images bitwise equal:        %s\n", test::farm::sameBits(embedded, farmed) ? "yes" : "NO");

    // 2. The master's cost per task.
    const int64_t tasks = farm.queryStore("SELECT COUNT(*) FROM results WHERE job_id = " + std::to_string(id));
    const double bytes =
        static_cast<double>(farm.queryStore("SELECT SUM(bytes) FROM results WHERE job_id = " + std::to_string(id))) /
        tasks;
    auto loaded = loadScene(copy);
    const auto integrator = makeIntegrator(*loaded, "", {});
    const ImageTaskResult r = runImageTask(*loaded, dynamic_cast<const SamplingIntegrator &>(*integrator), 1,
                                           ImageTask{0, imageTaskSize(spp, 0, int64_t{res} * res)}, 2);
    constexpr int kRepeats = 10;
    std::string payload;
    const auto e0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRepeats; ++i) payload = farm::encodeBlock(r.block);
    const double encodeSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - e0).count() / kRepeats;
    ImageBlock merged = makeFilmBlock(*loaded), decoded = makeFilmBlock(*loaded);
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRepeats; ++i) {
        farm::decodeBlock(payload, decoded);
        merged.merge(decoded);
    }
    const double mergeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / kRepeats;
    const double cpuPerTask = masterCpu / static_cast<double>(tasks);
    int64_t largest = 0;
    const int64_t pixels = int64_t{res} * res;
    for (int64_t first = 0; first < spp; first += imageTaskSize(spp, first, pixels))
        largest = std::max(largest, imageTaskSize(spp, first, pixels));
    std::printf("tasks:                       %8lld of %lld to %lld spp\n", static_cast<long long>(tasks),
                static_cast<long long>(imageTaskSize(spp, 0, pixels)), static_cast<long long>(largest));
    std::printf("result on the wire:          %8.3f MB per task (%.2f bytes per pixel; raw doubles: 56)\n", bytes / 1e6,
                bytes / (static_cast<double>(res) * res));
    std::printf("encode (worker):             %8.2f ms per task (in-process)\n", 1e3 * encodeSeconds);
    std::printf("decode + merge:              %8.2f ms per task (in-process)\n", 1e3 * mergeSeconds);
    std::printf("master CPU:                  %8.2f ms per task (whole process over the job)\n", 1e3 * cpuPerTask);

    // 3. Workers of 8 cores one master keeps busy: an 8-core worker renders a task in a quarter of the
    //    2-thread time; the master serves one task per cpuPerTask on one core (merges of a job are serial).
    const double taskSeconds8 = farmSeconds / static_cast<double>(tasks) * 2.0 / 8.0;
    std::printf("task time on an 8-core worker: %6.3f s\n", taskSeconds8);
    std::printf("8-core workers per master:   %8.0f  (by master CPU; %0.f by decode + merge alone; goal >= 500)\n",
                taskSeconds8 / cpuPerTask, taskSeconds8 / mergeSeconds);
    std::printf("8-core workers per 10 Gbit/s: %7.0f  (by result bytes)\n", taskSeconds8 * 1.25e9 / bytes);
    return taskSeconds8 / (samples / static_cast<double>(tasks));
}

double msSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

// A chain job's results as pathfarm-worker returns them (job seed 1, a time budget): each seeding task's, a
// direct-component task's block (one sample per pixel), and the sums of the first n chain tasks' results for
// n = 1..K, as a batch of n returns them (a larger batch's sum is hardly larger than K's).
struct ChainPayloads {
    std::vector<std::string> seeding;
    std::string direct;
    std::vector<std::string> chainSums;
    double taskSeconds = 0;  // a chain task's mean core-seconds
};

// Part 5; fills `payloads` for part 6.
void chainResults(const std::string &scene, const std::string &name, const NameValues &params, int count,
                  ChainPayloads &payloads) {
    auto loaded = loadScene(scene);
    const auto integrator = makeIntegrator(*loaded, name, params);
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*integrator);
    ChainJob job(*loaded, chains, 1, 0);
    for (uint64_t t = 0; t < job.seedingTaskCount(); ++t) {
        SeedingResult seeding = chains.runSeeding(*loaded, 0, 1, job.seedingTask(t));
        payloads.seeding.push_back(farm::encodeSeedingResult(seeding));
        job.mergeSeeding(std::move(seeding));
    }
    if (chains.directIntegrator())
        payloads.direct = farm::encodeBlock(runDirectTask(*loaded, chains, 1, ImageTask{0, 1}, 2).block);
    std::vector<ChainTask> tasks;
    for (uint64_t t = job.firstChainTask(); static_cast<int>(tasks.size()) < count; ++t)
        if (job.phaseOf(t) == ChainJob::Phase::Chain) tasks.push_back(job.chainTask(t));
    std::vector<std::optional<ChainResult>> results(tasks.size());
    std::atomic<size_t> next{0};
    const auto run = [&] {
        for (size_t i; (i = next++) < tasks.size();) results[i].emplace(runChainTask(*loaded, chains, 1, tasks[i]));
    };
    std::thread other(run);
    run();
    other.join();

    const Film &film = loaded->sensor().film();
    std::printf("%s, %s at %dx%d: chain task results, tiles (now) and dense (before)\n", scene.c_str(), name.c_str(),
                film.cropWidth(), film.cropHeight());
    std::printf(
        "task  mutations  task s  tiles (of all)  film MB tiles/dense  wire KB tiles/dense  encode ms tiles/dense  "
        "decode+merge ms tiles/dense\n");
    ChainImage now(makeFilmBlock(*loaded)), before(makeFilmBlock(*loaded));
    double sums[8] = {};
    for (size_t i = 0; i < results.size(); ++i) {
        const ChainResult &r = *results[i];
        ChainResult dense = r;
        dense.film = makeFilmBlock(*loaded);
        dense.film.merge(r.film);
        double row[8] = {sizeof(double) * r.film.storedValues() / 1e6,
                         sizeof(double) * dense.film.storedValues() / 1e6};
        auto t0 = std::chrono::steady_clock::now();
        const std::string tilesWire = farm::encodeChainResult(r);
        row[4] = msSince(t0);
        t0 = std::chrono::steady_clock::now();
        const std::string denseWire = farm::encodeChainResult(dense);
        row[5] = msSince(t0);
        row[2] = tilesWire.size() / 1e3, row[3] = denseWire.size() / 1e3;
        t0 = std::chrono::steady_clock::now();
        mergeChainResult(now, farm::decodeChainResult(tilesWire, makeFilmBlock(*loaded, BlockStorage::Tiles)));
        row[6] = msSince(t0);
        t0 = std::chrono::steady_clock::now();
        mergeChainResult(before, farm::decodeChainResult(denseWire, makeFilmBlock(*loaded)));
        row[7] = msSince(t0);
        size_t present = 0;
        for (size_t t = 0; t < r.film.tiles()->tileCount(); ++t) present += !r.film.tiles()->tile(t).empty();
        std::printf("%4zu %10llu %7.2f %5zu/%zu  %8.2f / %6.2f  %8.1f / %7.1f  %8.2f / %8.2f  %9.2f / %8.2f\n", i,
                    static_cast<unsigned long long>(r.mutations), r.seconds, present, r.film.tiles()->tileCount(),
                    row[0], row[1], row[2], row[3], row[4], row[5], row[6], row[7]);
        for (int k = 0; k < 8; ++k) sums[k] += row[k];
    }
    const double n = static_cast<double>(results.size());
    std::printf("mean                                   %8.2f / %6.2f  %8.1f / %7.1f  %8.2f / %8.2f  %9.2f / %8.2f\n",
                sums[0] / n, sums[1] / n, sums[2] / n, sums[3] / n, sums[4] / n, sums[5] / n, sums[6] / n, sums[7] / n);
    const auto bits = [](std::span<const double> a, std::span<const double> b) {
        return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
    };
    // The same K results as one batch (pathfarm-worker --batch K, worker/chain_batch.h): summed in task order on
    // the worker, encoded once, decoded and merged once on the master.
    auto t0 = std::chrono::steady_clock::now();
    ChainResult sum = *results.front();
    for (size_t i = 1; i < results.size(); ++i) addChainResult(sum, *results[i]);
    const double sumMs = msSince(t0);
    {
        ChainResult prefix = *results.front();
        payloads.chainSums.push_back(farm::encodeChainResult(prefix));
        for (size_t i = 1; i < results.size(); ++i) {
            addChainResult(prefix, *results[i]);
            payloads.chainSums.push_back(farm::encodeChainResult(prefix));
        }
        for (const auto &r : results) payloads.taskSeconds += r->seconds / n;
    }
    t0 = std::chrono::steady_clock::now();
    const std::string batchWire = farm::encodeChainResult(sum);
    const double encodeMs = msSince(t0);
    ChainImage batched(makeFilmBlock(*loaded));
    batched.film.clear();  // its pages touched before the clock starts, as those of `now` are by now
    t0 = std::chrono::steady_clock::now();
    mergeChainResult(batched, farm::decodeChainResult(batchWire, makeFilmBlock(*loaded, BlockStorage::Tiles)),
                     results.size());
    const double mergeMs = msSince(t0);
    std::printf(
        "as one batch of %zu: film %.2f MB, wire %.1f KB (%.1f KB per task, %.1fx fewer bytes than single results), "
        "summing on the worker %.2f ms, encode %.2f ms, decode+merge %.2f ms (%.2f ms per task)\n",
        results.size(), sizeof(double) * sum.film.storedValues() / 1e6, batchWire.size() / 1e3,
        batchWire.size() / 1e3 / n, sums[2] / (batchWire.size() / 1e3), sumMs, encodeMs, mergeMs, mergeMs / n);
    std::printf("merged films bitwise equal: %s\n", bits(now.film.splatData(), before.film.splatData()) &&
                                                            bits(now.film.sumData(), before.film.sumData()) &&
                                                            bits(now.film.weightData(), before.film.weightData())
                                                        ? "yes"
                                                        : "NO");
}

// Part 6: a chain job of integrator NAME under a time budget of `seconds` on a fresh master, at the scene's own
// size, with `workers` fake workers returning part 5's results at once (chain tasks as the batch's sum); the
// master's CPU per chain task, and the 8-core workers it keeps busy at part 5's chain task time.
void saturateChains(const std::string &scene, const std::string &name, const std::vector<std::string> &params,
                    int workers, int batch, double seconds, const ChainPayloads &payloads) {
    test::farm::Farm farm("bench-saturate-chains");
    test::farm::Process &master = farm.startMaster();
    const PayloadFor payloadFor = [&](const v1::LeaseReply &lease) -> std::pair<const std::string *, uint64_t> {
        const v1::TaskSpec &t = lease.task();
        if (t.has_seeding()) return {&payloads.seeding.at(static_cast<size_t>(t.task_index())), 0};
        if (t.has_image()) return {&payloads.direct, 0};
        const size_t n = std::min<size_t>(1 + static_cast<size_t>(lease.more_size()), payloads.chainSums.size());
        return {&payloads.chainSums[n - 1], 0};
    };
    const Saturated r = runSaturated(farm, master, workers, batch, payloadFor, [&] {
        std::string args = "submit " + fs::absolute(scene).string() + " --integrator " + name + " --time " +
                           std::to_string(seconds) + " --seed 1";
        for (const std::string &p : params) args += " -P " + p;
        return args;
    });
    const v1::ChainStats &c = r.job.chain();
    // A finished job merged whole passes; its direct tasks hold one or more samples each (render/chain_job.h).
    const auto chainTasks = static_cast<int64_t>(c.passes() * c.tasks_per_pass());
    const int64_t direct = r.job.tasks().merged() - static_cast<int64_t>(c.seeding_tasks()) - chainTasks;
    const double n = static_cast<double>(std::max<int64_t>(1, chainTasks));
    // Seeding and direct tasks are never batched: the other results are the chain tasks'.
    const int64_t chainResults = r.returned - static_cast<int64_t>(c.seeding_tasks()) - direct;
    std::printf(
        "chain saturation: %d fake workers, batches of %s (%.1f tasks per result, %.1f per chain result), %s: %lld "
        "chain tasks (and %llu seeding, %lld direct) in %.2f s\n",
        workers, batch == farm::kAutoBatch ? "auto" : std::to_string(batch).c_str(),
        static_cast<double>(r.leased) / static_cast<double>(std::max<int64_t>(1, r.returned)),
        static_cast<double>(chainTasks) / static_cast<double>(std::max<int64_t>(1, chainResults)), name.c_str(),
        static_cast<long long>(chainTasks), static_cast<unsigned long long>(c.seeding_tasks()),
        static_cast<long long>(direct), r.wall);
    std::printf("  master CPU:                %8.3f ms per chain task (the job's whole CPU over its chain tasks)\n",
                1e3 * r.cpu / n);
    std::printf("  chain tasks per CPU-second: %7.1f  (master CPU %.0f%% of one core; the machine may be shared)\n",
                n / r.cpu, 100 * r.cpu / r.wall);
    std::printf("  bytes per chain task:      %8.0f  (protobuf messages both ways)\n",
                static_cast<double>(r.bytes) / n);
    std::printf("  8-core workers per master:  %7.1f at chain tasks of %.3f core-seconds\n",
                (n / r.cpu) * payloads.taskSeconds / 8, payloads.taskSeconds);
}

}  // namespace

int main(int argc, char **argv) {
    std::string scene = std::string(PATHFARM_SOURCE_DIR) + "/scenes/cornell-box/scene.xml";
    int res = 256, spp = 64, fakeWorkers = 32, fakeRes = 0;  // 0: --res
    int64_t fakeTasks = 400;
    std::vector<int> batches{1};
    double taskSeconds = 0;
    bool fakeOnly = false;
    std::string chain;
    int chainTasks = 8;
    double chainFarmSeconds = 0;
    std::vector<std::string> chainParams;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool value = i + 1 < argc;
        if (a == "--res" && value) {
            res = std::stoi(argv[++i]);
        } else if (a == "--spp" && value) {
            spp = std::stoi(argv[++i]);
        } else if (a == "--fake-workers" && value) {
            fakeWorkers = std::stoi(argv[++i]);
        } else if (a == "--fake-tasks" && value) {
            fakeTasks = std::stoll(argv[++i]);
        } else if (a == "--fake-res" && value) {
            fakeRes = std::stoi(argv[++i]);
        } else if (a == "--fake-batch" && value) {
            batches.clear();
            std::stringstream list(argv[++i]);
            for (std::string n; std::getline(list, n, ',');)
                batches.push_back(n == "auto" ? farm::kAutoBatch : std::stoi(n));
        } else if (a == "--task-seconds" && value) {
            taskSeconds = std::stod(argv[++i]);
        } else if (a == "--fake-only") {
            fakeOnly = true;
        } else if (a == "--chain" && value) {
            chain = argv[++i];
        } else if (a == "--chain-tasks" && value) {
            chainTasks = std::stoi(argv[++i]);
        } else if (a == "--chain-farm" && value) {
            chainFarmSeconds = std::stod(argv[++i]);
        } else if (a == "-P" && value) {
            chainParams.push_back(argv[++i]);
        } else if (a.rfind("--", 0) == 0) {
            std::fprintf(stderr, "bench_farm: unknown option %s\n", a.c_str());
            return 2;
        } else {
            scene = a;
        }
    }
    if (!chain.empty()) {
        ChainPayloads payloads;
        chainResults(scene, chain, parseNameValues(chainParams, "-P"), chainTasks, payloads);
        if (chainFarmSeconds > 0)
            for (const int batch : batches)
                saturateChains(scene, chain, chainParams, fakeWorkers, batch, chainFarmSeconds, payloads);
        return 0;
    }
    const double sampleSeconds8 = fakeOnly ? 0 : realFarm(scene, res, spp);
    std::map<int64_t, std::string> results;
    for (const int batch : batches)
        saturate(scene, fakeRes > 0 ? fakeRes : res, fakeWorkers, fakeTasks, sampleSeconds8, batch, taskSeconds,
                 results);
    return 0;
}
