// Farm overhead and master cost per task, with real processes on loopback. Prints figures; never
// passes or fails on time.
//
//   bench_farm [SCENE] [--res N] [--spp N]     (default: scenes/cornell-box/scene.xml at 256x256, 64 spp)
//
// 1. The same job rendered embedded (`pathfarm render --threads 2`) and by a farm of one local worker
//    with 2 threads: samples/s of each and their ratio (farm time runs from the first lease to the
//    last merge, so it includes the worker fetching the bundle and loading the scene).
// 2. What a task costs the master: CPU seconds of the master process per task over the whole job
//    (gRPC, validation, storing, merging, checkpoints, leases), the decode + merge time of one result
//    measured in-process, and the bytes of a result on the wire.
// 3. From these, how many 8-core workers one master can keep busy at this task size.
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "farm/block_codec.h"
#include "farm/harness.h"
#include "farm/job_setup.h"
#include "farm/rpc.h"
#include "image/bitmap.h"
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

}  // namespace

int main(int argc, char **argv) {
    std::string scene = std::string(PATHFARM_SOURCE_DIR) + "/scenes/cornell-box/scene.xml";
    int res = 256, spp = 64;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--res" && i + 1 < argc) {
            res = std::stoi(argv[++i]);
        } else if (a == "--spp" && i + 1 < argc) {
            spp = std::stoi(argv[++i]);
        } else {
            scene = a;
        }
    }
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
            return 1;
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
            return 1;
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
                                           ImageTask{0, imageTaskSize(spp, 0)}, 2);
    const std::string payload = farm::encodeBlock(r.block);
    ImageBlock merged = makeFilmBlock(*loaded), decoded = makeFilmBlock(*loaded);
    constexpr int kRepeats = 10;
    const auto t0 = std::chrono::steady_clock::now();
    for (int i = 0; i < kRepeats; ++i) {
        farm::decodeBlock(payload, decoded);
        merged.merge(decoded);
    }
    const double mergeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / kRepeats;
    const double cpuPerTask = masterCpu / static_cast<double>(tasks);
    int64_t largest = 0;
    for (int64_t first = 0; first < spp; first += imageTaskSize(spp, first))
        largest = std::max(largest, imageTaskSize(spp, first));
    std::printf("tasks:                       %8lld of %lld to %lld spp\n", static_cast<long long>(tasks),
                static_cast<long long>(imageTaskSize(spp, 0)), static_cast<long long>(largest));
    std::printf("result on the wire:          %8.3f MB per task (%.2f bytes per pixel; raw doubles: 56)\n", bytes / 1e6,
                bytes / (static_cast<double>(res) * res));
    std::printf("decode + merge:              %8.2f ms per task (in-process)\n", 1e3 * mergeSeconds);
    std::printf("master CPU:                  %8.2f ms per task (whole process over the job)\n", 1e3 * cpuPerTask);

    // 3. Workers of 8 cores one master keeps busy: an 8-core worker renders a task in a quarter of the
    //    2-thread time; the master serves one task per cpuPerTask on one core (merges of a job are serial).
    const double taskSeconds8 = farmSeconds / static_cast<double>(tasks) * 2.0 / 8.0;
    std::printf("task time on an 8-core worker: %6.3f s\n", taskSeconds8);
    std::printf("8-core workers per master:   %8.0f  (by master CPU; %0.f by decode + merge alone; goal >= 500)\n",
                taskSeconds8 / cpuPerTask, taskSeconds8 / mergeSeconds);
    std::printf("8-core workers per 10 Gbit/s: %7.0f  (by result bytes)\n", taskSeconds8 * 1.25e9 / bytes);
    return 0;
}
