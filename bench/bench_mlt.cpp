// Veach's path-space MLT and ERPT on a scene (default: the shared veach-bidir, Veach's own test of the
// bidirectional mutation): chain throughput, acceptance per mutation type, and the error at equal time
// against BDPT.
//
//   bench_mlt [--res N] [--mpp N] [--seed-spp N] [--threads N] [--ref-spp N] [--time S] [--runs K] [--out DIR]
//             [scene.xml]
//
// 1. Per core, at N x N (default 64): `mlt` with mpp mutations per pixel (default 64) and `erpt` with
//    seed-spp seed samples per pixel (default 16), both with Mitsuba's defaults otherwise, run as the
//    embedded renderer runs them (seeding tasks, the normalizer, chain tasks) on one thread: mutations per
//    second and per CPU second (comparable on a shared machine) of the chain tasks, and per mutation type the
//    proposals, acceptances and acceptance rate.
// 2. Equal time at N x N: a BDPT reference with ref-spp samples per pixel (default 4096), then K runs
//    (default 3, different seeds) of bdpt, mlt and erpt with about S seconds each (default 10) on
//    `threads` threads (default: all cores), and their relative mean squared error against the
//    reference, the mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2), also without the worst
//    0.1% of the pixels (one bright outlier can hold most of it). bdpt and mlt run with a time budget;
//    erpt's budget is its seeds per pixel (the scene's sampleCount), so it runs at the seed count that
//    a calibration run says fills S seconds. --out writes the reference and each method's first image
//    as EXR. Prints figures only; it never passes or fails.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "image/bitmap.h"
#include "integrators/erpt.h"
#include "integrators/mlt.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "scene/scene.h"

namespace {

namespace fs = std::filesystem;

struct Options {
    int res = 64, mpp = 64, seedSpp = 16, refSpp = 4096, runs = 3;
    int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    double seconds = 10;
    std::string scene = "scenes/veach-bidir/scene.xml", out;
};

// `type` with the scene file's maxDepth and, for erpt, chainLength `chainLength` (0: the default).
std::unique_ptr<pf::Integrator> makeIntegrator(const pf::Scene &scene, const std::string &type, int chainLength = 0) {
    pf::Properties props(pf::ObjectKind::Integrator, type, {});
    const pf::Properties &file = scene.integratorProperties();
    if (file.has("maxDepth")) props.set("maxDepth", pf::Properties::Type::Integer, file.getInt("maxDepth"), {});
    if (chainLength > 0) props.set("chainLength", pf::Properties::Type::Integer, int64_t(chainLength), {});
    return pf::createIntegrator(type, props, true);
}

double secondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// Seeding, normalizer and chain tasks on the calling thread, as the embedded renderer runs them.
pf::ChainImage runChains(const pf::Scene &scene, const pf::ChainIntegrator &integrator, int64_t spp,
                         double &chainSeconds, double &chainCpuSeconds) {
    std::vector<pf::SeedingResult> seeds;
    for (const pf::SeedingTask &t : integrator.seedingTasks(scene))
        seeds.push_back(integrator.runSeeding(scene, 0, 1, t));
    const pf::Normalizer normalizer(std::move(seeds));
    pf::ChainImage image(pf::makeFilmBlock(scene));
    const auto start = std::chrono::steady_clock::now();
    const double cpuStart = bench::processCpuSeconds();
    for (uint64_t i = 0; i < integrator.chainTaskCount(scene, spp); ++i)
        pf::mergeChainResult(
            image, pf::runChainTask(scene, integrator, 1, integrator.chainTask(scene, normalizer, 1, spp, i)));
    chainSeconds = secondsSince(start);
    chainCpuSeconds = bench::processCpuSeconds() - cpuStart;
    return image;
}

}  // namespace

int main(int argc, char **argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool value = i + 1 < argc;
        if (a == "--res" && value)
            o.res = std::stoi(argv[++i]);
        else if (a == "--mpp" && value)
            o.mpp = std::stoi(argv[++i]);
        else if (a == "--seed-spp" && value)
            o.seedSpp = std::stoi(argv[++i]);
        else if (a == "--threads" && value)
            o.threads = std::stoi(argv[++i]);
        else if (a == "--ref-spp" && value)
            o.refSpp = std::stoi(argv[++i]);
        else if (a == "--time" && value)
            o.seconds = std::stod(argv[++i]);
        else if (a == "--runs" && value)
            o.runs = std::stoi(argv[++i]);
        else if (a == "--out" && value)
            o.out = argv[++i];
        else
            o.scene = a;
    }
    std::printf("%s, %d x %d\n", o.scene.c_str(), o.res, o.res);

    // 1. Per-core throughput and acceptance.
    const auto scene = bench::loadWithSampleCount(o.scene, o.seedSpp, o.res, "bench_mlt");
    for (const std::string type : {"mlt", "erpt"}) {
        const auto integrator = makeIntegrator(*scene, type);
        double seconds = 0, cpu = 0;
        const pf::ChainImage image = runChains(*scene, dynamic_cast<const pf::ChainIntegrator &>(*integrator),
                                               type == "mlt" ? o.mpp : o.seedSpp, seconds, cpu);
        std::printf("%s: %llu mutations in %.2f s on one core: %.4g mutations/s, %.4g per CPU second\n", type.c_str(),
                    static_cast<unsigned long long>(image.mutations), seconds,
                    static_cast<double>(image.mutations) / seconds, static_cast<double>(image.mutations) / cpu);
        std::printf("  %-14s %12s %12s %11s\n", "mutation", "proposed", "accepted", "acceptance");
        for (const pf::MutationCount &c : image.counts)
            std::printf("  %-14s %12llu %12llu %10.2f%%\n", c.name.c_str(), static_cast<unsigned long long>(c.proposed),
                        static_cast<unsigned long long>(c.accepted),
                        c.proposed ? 100.0 * static_cast<double>(c.accepted) / static_cast<double>(c.proposed) : 0.0);
    }

    // 2. Equal time.
    pf::RenderStats refStats;
    const auto bdpt = makeIntegrator(*scene, "bdpt");
    const pf::Bitmap reference = bench::renderWith(*scene, *bdpt, o.refSpp, 0, 1000, o.threads, refStats);
    std::printf("reference: bdpt, %d spp, %.1f s\n", o.refSpp, refStats.seconds);
    if (!o.out.empty()) pf::writeEXR(o.out + "/reference.exr", reference);
    struct Method {
        std::string label, type;
        int chainLength;  // erpt's, 0: the default
    };
    std::printf("%-14s %4s %9s %9s %12s %16s\n", "", "run", "seconds", "budget", "relMSE", "w/o worst 0.1%");
    for (const Method &m : {Method{"bdpt", "bdpt", 0}, Method{"mlt", "mlt", 0}, Method{"erpt", "erpt", 0},
                            Method{"erpt-1000", "erpt", 1000}}) {
        const bool timed = m.type != "erpt";
        int seeds = 0;
        if (!timed) {
            // ERPT's seeds per pixel for S seconds, from the times of runs with 1 and 3 seeds per pixel (a
            // fixed part, the direct component, and a part proportional to the seeds).
            double probe[2];
            for (int k = 0; k < 2; ++k) {
                const auto probeScene = bench::loadWithSampleCount(o.scene, 1 + 2 * k, o.res, "bench_mlt");
                pf::RenderStats stats;
                bench::renderWith(*probeScene, *makeIntegrator(*probeScene, m.type, m.chainLength), 0, 0, 1, o.threads,
                                  stats);
                probe[k] = stats.seconds;
            }
            const double perSeed = std::max(1e-9, (probe[1] - probe[0]) / 2), fixed = probe[0] - perSeed;
            seeds = std::max(1, static_cast<int>((o.seconds - fixed) / perSeed));
        }
        const auto methodScene = timed ? nullptr : bench::loadWithSampleCount(o.scene, seeds, o.res, "bench_mlt");
        const pf::Scene &s = timed ? *scene : *methodScene;
        const auto integrator = makeIntegrator(s, m.type, m.chainLength);
        bench::RelativeError mean;
        for (int run = 0; run < o.runs; ++run) {
            pf::RenderStats stats;
            const pf::Bitmap image = bench::renderWith(s, *integrator, seeds, timed ? o.seconds : 0,
                                                       static_cast<uint64_t>(run + 1), o.threads, stats);
            const bench::RelativeError e = bench::relativeError(image, reference);
            mean.all += e.all / o.runs;
            mean.trimmed += e.trimmed / o.runs;
            std::printf("%-14s %4d %9.2f %9lld %12.4g %16.4g\n", m.label.c_str(), run, stats.seconds,
                        static_cast<long long>(timed ? stats.samplesPerPixel : seeds), e.all, e.trimmed);
            if (run == 0 && !o.out.empty()) pf::writeEXR(o.out + "/" + m.label + ".exr", image);
        }
        std::printf("%-14s mean relMSE %.4g (without the worst 0.1%%: %.4g)\n", m.label.c_str(), mean.all,
                    mean.trimmed);
    }
    return 0;
}
