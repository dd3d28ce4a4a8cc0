// Manifold exploration ([TR §8]; ALGORITHMS.md §5.4-5.5, §8.3) on the TORUS scene and veach-bidir: the
// statistics of Table 1 for MEPT and MEMLT, chain throughput per core, and the error at equal time of MEPT,
// MEMLT, ERPT and BDPT against a long BDPT reference.
//
//   bench_manifold [--res N] [--time S] [--ref-spp N] [--seed-spp N] [--mpp N] [--lambda L] [--threads N]
//                  [--out DIR] [scene.xml ...]
//
// 1. Table 1, per core (one thread, seeding excluded from the time): `mept` with seed-spp seeds per pixel
//    (default 4) and `memlt` with mpp mutations per pixel (default 32), lambda L (default 50): mutations,
//    acceptance, manifold walks per mutation, walks converged, mean Newton iterations, mean and largest
//    specular chain, reverse walks and non-reversible proposals, mutations/s.
// 2. Equal time at N x N (default 32): a BDPT reference with ref-spp samples per pixel (default 2048), then
//    bdpt and memlt with a time budget of S seconds (default 8) on `threads` threads (default: all cores),
//    and erpt and mept at the seeds per pixel that a one-seed probe says fill S seconds (bursts have no
//    clock: their budget is the seeding's). relMSE is the mean over pixels and channels of
//    (x - r)^2 / (r^2 + 1e-2). --out writes the reference and each method's image as EXR. Figures only.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "image/bitmap.h"
#include "integrators/integrator.h"
#include "render/chain.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "scene/scene.h"

namespace {

namespace fs = std::filesystem;

struct Options {
    int res = 32, refSpp = 2048, seedSpp = 4, mpp = 32;
    int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    double seconds = 8, lambda = 50;
    std::vector<std::string> scenes;
    std::string out;
};

std::unique_ptr<pf::Integrator> integrator(const pf::Scene &scene, const std::string &type, double lambda) {
    pf::Properties props(pf::ObjectKind::Integrator, type, {});
    const pf::Properties &file = scene.integratorProperties();
    if (file.has("maxDepth")) props.set("maxDepth", pf::Properties::Type::Integer, file.getInt("maxDepth"), {});
    if (type == "mept" || type == "memlt") props.set("lambda", pf::Properties::Type::Float, lambda, {});
    return pf::createIntegrator(type, props, true);
}

// Seeding, then the chain tasks one after the other on this thread; ChainImage::seconds sums the tasks' own
// times, so seeding stays out of the throughput.
pf::ChainImage chainsOnOneCore(const pf::Scene &scene, const pf::ChainIntegrator &chains, int64_t spp) {
    std::vector<pf::SeedingResult> seeding;
    for (const pf::SeedingTask &task : pf::seedingTasks(scene))
        seeding.push_back(pf::runSeedingTask(scene, chains.seeding(scene), 1, task));
    const pf::Normalizer normalizer(std::move(seeding));
    pf::ChainImage image(pf::makeFilmBlock(scene));
    for (uint64_t k = 0; k < chains.chainTaskCount(scene, spp); ++k)
        pf::mergeChainResult(image, pf::runChainTask(scene, chains, 1, chains.chainTask(scene, normalizer, 1, spp, k)));
    return image;
}

void printTable1(const std::string &label, const pf::ChainImage &image) {
    uint64_t proposed = 0, accepted = 0;
    for (const pf::MutationCount &c : image.counts) proposed += c.proposed, accepted += c.accepted;
    pf::ChainCounters counters = image.counters;
    const auto value = [&](const char *name) { return pf::counter(counters, name).value; };
    const double walks = value("manifoldWalks"), reverse = value("manifoldReverseWalks");
    const double perWalk = walks > 0 ? 1 / walks : 0;
    std::printf("%-7s %11llu %8.1f%% %10.0f %7.2f %8.1f%% %7.2f %6.2f %4.0f %9.0f %6.2f%% %11.4g\n", label.c_str(),
                static_cast<unsigned long long>(proposed), proposed ? 100.0 * accepted / proposed : 0.0, walks,
                proposed ? walks / proposed : 0.0, 100 * value("manifoldWalksConverged") * perWalk,
                value("manifoldNewtonIterations") * perWalk, value("manifoldChainVertices") * perWalk,
                value("manifoldChainVerticesMax"), reverse,
                reverse > 0 ? 100 * value("manifoldNonReversible") / reverse : 0.0,
                image.seconds > 0 ? static_cast<double>(image.mutations) / image.seconds : 0.0);
    for (const pf::MutationCount &c : image.counts)
        if (c.proposed > 0)
            std::printf("        %-14s %llu proposed, %.1f%% accepted\n", c.name.c_str(),
                        static_cast<unsigned long long>(c.proposed), 100.0 * c.accepted / c.proposed);
}

void benchScene(const Options &o, const std::string &path) {
    std::printf("\n== %s, %d x %d, lambda %g\n", path.c_str(), o.res, o.res, o.lambda);
    std::printf("%-7s %11s %9s %10s %7s %9s %7s %6s %4s %9s %7s %11s\n", "method", "mutations", "accepted", "walks",
                "walks/m", "converged", "Newton", "size", "max", "reverse", "nonrev", "mutations/s");
    const auto scene = bench::loadWithSampleCount(path, o.seedSpp, o.res, "bench_manifold");
    for (const std::string type : {"mept", "memlt"}) {
        const auto method = integrator(*scene, type, o.lambda);
        printTable1(type, chainsOnOneCore(*scene, dynamic_cast<const pf::ChainIntegrator &>(*method),
                                          type == "mept" ? o.seedSpp : o.mpp));
    }

    pf::RenderStats refStats;
    const pf::Bitmap reference =
        bench::renderWith(*scene, *integrator(*scene, "bdpt", o.lambda), o.refSpp, 0, 7, o.threads, refStats);
    std::printf("reference: bdpt %d spp in %.1f s\n", o.refSpp, refStats.seconds);
    const std::string stem = o.out.empty() ? "" : o.out + "/" + fs::path(path).parent_path().filename().string();
    if (!stem.empty()) pf::writeEXR(stem + "-reference.exr", reference);
    std::printf("%-7s %9s %9s %12s\n", "method", "seconds", "budget", "relMSE");
    for (const std::string type : {"bdpt", "memlt", "erpt", "mept"}) {
        const bool bursts = type == "erpt" || type == "mept";
        int64_t seeds = 0;
        std::unique_ptr<pf::Scene> burstScene;
        if (bursts) {
            // Seeds per pixel for S seconds from a one-seed probe (its time is mostly per seed).
            const auto probeScene = bench::loadWithSampleCount(path, 1, o.res, "bench_manifold");
            pf::RenderStats probe;
            bench::renderWith(*probeScene, *integrator(*probeScene, type, o.lambda), 0, 0, 7, o.threads, probe);
            seeds = std::max<int64_t>(1, static_cast<int64_t>(o.seconds / std::max(probe.seconds, 1e-3)));
            burstScene = bench::loadWithSampleCount(path, static_cast<int>(seeds), o.res, "bench_manifold");
        }
        const pf::Scene &s = bursts ? *burstScene : *scene;
        pf::RenderStats stats;
        const pf::Bitmap image =
            bench::renderWith(s, *integrator(s, type, o.lambda), seeds, bursts ? 0 : o.seconds, 7, o.threads, stats);
        std::printf("%-7s %9.2f %9lld %12.4g\n", type.c_str(), stats.seconds,
                    static_cast<long long>(bursts ? seeds : stats.samplesPerPixel),
                    bench::relativeError(image, reference).all);
        if (!stem.empty()) pf::writeEXR(stem + "-" + type + ".exr", image);
    }
}

}  // namespace

int main(int argc, char **argv) {
    Options o;
    const std::map<std::string, std::function<void(const char *)>> flags = {
        {"--res", [&](const char *v) { o.res = std::stoi(v); }},
        {"--time", [&](const char *v) { o.seconds = std::stod(v); }},
        {"--ref-spp", [&](const char *v) { o.refSpp = std::stoi(v); }},
        {"--seed-spp", [&](const char *v) { o.seedSpp = std::stoi(v); }},
        {"--mpp", [&](const char *v) { o.mpp = std::stoi(v); }},
        {"--lambda", [&](const char *v) { o.lambda = std::stod(v); }},
        {"--threads", [&](const char *v) { o.threads = std::stoi(v); }},
        {"--out", [&](const char *v) { o.out = v; }}};
    for (int i = 1; i < argc; ++i) {
        const auto flag = flags.find(argv[i]);
        if (flag != flags.end() && i + 1 < argc)
            flag->second(argv[++i]);
        else
            o.scenes.push_back(argv[i]);
    }
    if (o.scenes.empty()) o.scenes = {"scenes/torus/scene.xml", "scenes/veach-bidir/scene.xml"};
    try {
        for (const std::string &path : o.scenes) benchScene(o, path);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
