// Path tracer throughput against raw Embree traversal on the same scene (issue 3's performance goal:
// the path tracer sustains at least 50% of the raw incoherent rtcIntersect1 rate).
//
//   bench_pathtracer [--res N] [--spp N] [--threads N] scene.xml ...
//
// Raw rate: random rays (origins uniform in the scene bounds, directions uniform on the sphere),
// generated before timing, traced with rtcIntersect1 on every thread. Path tracer rate: rays/s and
// samples/s of `path` at N x N (default 512), scene load and BVH build excluded. Each rate is also printed
// per second of the process's CPU time, the figure to compare on a machine shared with other work, where
// wall-clock rates follow the load. Prints figures only; it never passes or fails on time.
//
// Random rays are a kinder yardstick on some scenes than the path tracer's own, which start on surfaces in
// the densest geometry and end at the lights (on veach-bidir Embree spends 1.9x as long on a path ray). So a
// second table replays the rays of a one-sample-per-pixel render of the same film, recorded in the order the
// path tracer traced them (Scene::recordThreadRays), through raw Embree alone (intersect or occlusion
// query, as recorded), split among the threads: the path tracer's rate over that one is the share of its
// time that Embree's traversal takes.
#include <embree3/rtcore.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "core/rng.h"
#include "core/warp.h"
#include "image/film.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace {

struct Rate {
    double wall, cpu;  // per second of wall-clock time and of process CPU time
    size_t rays = 0;   // rays traced
};

Rate rawEmbreeRaysPerSecond(const pf::Scene &scene, int threads, size_t raysPerThread) {
    const pf::AABB b = scene.bounds();
    std::vector<std::vector<RTCRayHit>> rays(threads);
    for (int t = 0; t < threads; ++t) {
        pf::PCG32 rng(42, t);
        rays[t].resize(raysPerThread);
        for (RTCRayHit &rh : rays[t]) {
            std::memset(&rh, 0, sizeof rh);
            const pf::Vec3 o(pf::lerp(rng.nextDouble(), b.min.x, b.max.x), pf::lerp(rng.nextDouble(), b.min.y, b.max.y),
                             pf::lerp(rng.nextDouble(), b.min.z, b.max.z));
            const pf::Vec3 d = pf::warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()});
            rh.ray.org_x = float(o.x), rh.ray.org_y = float(o.y), rh.ray.org_z = float(o.z);
            rh.ray.dir_x = float(d.x), rh.ray.dir_y = float(d.y), rh.ray.dir_z = float(d.z);
            rh.ray.tnear = 0.0f;
            rh.ray.tfar = std::numeric_limits<float>::infinity();
            rh.ray.mask = 0xFFFFFFFFu;
            rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        }
    }
    const auto start = std::chrono::steady_clock::now();
    const double cpuStart = bench::processCpuSeconds();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            for (RTCRayHit &rh : rays[t]) rtcIntersect1(scene.embreeScene(), &ctx, &rh);
        });
    for (auto &th : pool) th.join();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double traced = static_cast<double>(threads * raysPerThread);
    return {traced / secs, traced / (bench::processCpuSeconds() - cpuStart)};
}

// Records the rays of a one-sample-per-pixel render on this thread, then traces them again through Embree
// alone, each thread a contiguous share of them in the recorded order.
Rate replayedRaysPerSecond(const pf::Scene &scene, const pf::Integrator &integrator, int threads) {
    std::vector<pf::Scene::TracedRay> log;
    pf::RenderOptions opt;
    opt.spp = 1;
    opt.threads = 1;  // the render runs on the calling thread, the one that records
    pf::RenderStats stats;
    pf::Scene::recordThreadRays(&log);
    integrator.render(scene, opt, stats);
    pf::Scene::recordThreadRays(nullptr);

    // Each thread traces its share several times over, so that the timing spans about a second rather than
    // a tenth of one; its hit count stays in a local, away from the other threads' cache lines.
    constexpr int kRepeats = 8;
    const size_t share = (log.size() + threads - 1) / threads;
    std::vector<size_t> hits(threads, 0);  // kept, so that the queries are not optimized away
    const auto start = std::chrono::steady_clock::now();
    const double cpuStart = bench::processCpuSeconds();
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            const size_t end = std::min(log.size(), (t + 1) * share);
            size_t hit = 0;
            for (int k = 0; k < kRepeats; ++k)
                for (size_t i = t * share; i < end; ++i) hit += scene.traverse(log[i]);
            hits[t] = hit;
        });
    for (auto &th : pool) th.join();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double cpu = bench::processCpuSeconds() - cpuStart;
    size_t hit = 0;
    for (const size_t h : hits) hit += h;
    if (hit > kRepeats * log.size()) std::abort();  // never: it only keeps the results alive
    const double traced = static_cast<double>(kRepeats * log.size());
    return {traced / secs, traced / cpu, log.size()};
}

}  // namespace

int main(int argc, char **argv) {
    int res = 512, spp = 8, threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    std::vector<std::string> scenes;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--res" && i + 1 < argc)
            res = std::stoi(argv[++i]);
        else if (a == "--spp" && i + 1 < argc)
            spp = std::stoi(argv[++i]);
        else if (a == "--threads" && i + 1 < argc)
            threads = std::stoi(argv[++i]);
        else
            scenes.push_back(a);
    }
    std::printf("%-36s %7s %13s %13s %13s %7s | %13s %13s %13s %7s\n", "scene", "threads", "embree rays/s",
                "path rays/s", "samples/s", "ratio", "embree /cpu-s", "path /cpu-s", "samples/cpu-s", "ratio");
    std::vector<std::string> replayLines;
    for (const std::string &path : scenes) {
        auto scene = pf::loadScene(path);
        scene->resizeFilm(res, res);
        const Rate raw = rawEmbreeRaysPerSecond(*scene, threads, 2000000);
        auto integrator = pf::createIntegrator("path", scene->integratorProperties(), false);
        pf::RenderOptions opt;
        opt.spp = spp;
        opt.threads = threads;
        pf::RenderStats stats;
        const double cpuStart = bench::processCpuSeconds();
        integrator->render(*scene, opt, stats);
        const double cpu = bench::processCpuSeconds() - cpuStart;
        const double rays = stats.rays / stats.seconds, samples = stats.samples / stats.seconds;
        const double cpuRays = stats.rays / cpu, cpuSamples = stats.samples / cpu;
        std::printf("%-36s %7d %13.4g %13.4g %13.4g %6.1f%% | %13.4g %13.4g %13.4g %6.1f%%\n", path.c_str(), threads,
                    raw.wall, rays, samples, 100.0 * rays / raw.wall, raw.cpu, cpuRays, cpuSamples,
                    100.0 * cpuRays / raw.cpu);
        const Rate replay = replayedRaysPerSecond(*scene, *integrator, threads);
        char line[256];
        std::snprintf(line, sizeof line, "%-36s %7d %9zu %15.4g %7.1f%% | %15.4g %7.1f%%", path.c_str(), threads,
                      replay.rays, replay.wall, 100.0 * rays / replay.wall, replay.cpu, 100.0 * cpuRays / replay.cpu);
        replayLines.emplace_back(line);
    }
    std::printf("\nthe path tracer's own rays (one sample per pixel), replayed through raw Embree:\n");
    std::printf("%-36s %7s %9s %15s %8s | %15s %8s\n", "scene", "threads", "rays", "replayed rays/s", "ratio",
                "replayed /cpu-s", "ratio");
    for (const std::string &line : replayLines) std::printf("%s\n", line.c_str());
    return 0;
}
