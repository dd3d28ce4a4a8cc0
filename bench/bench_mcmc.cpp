// PSSMLT and MMLT on a shared scene (default veach-bidir): chain throughput per core, acceptance per
// mutation type, and the error at equal time against a BDPT reference.
//
//   bench_mcmc [--res N] [--mpp N] [--threads N] [--ref-spp N] [--time S] [--runs K] [scene name]
//
// The scene (a directory under scenes/) is loaded at N x N (default 64) with a box reconstruction filter,
// so that BDPT's filtered samples and the chains' unfiltered splats estimate the same pixel integrals.
// 1. Per core: `pssmlt` and `mmlt` with Mitsuba's defaults, run as the embedded renderer runs them
//    (seeding tasks, the normalizer, chain tasks for mpp mutations per pixel, default 64) on one thread:
//    mutations per second and per CPU second (comparable on a shared machine) of the chain tasks, and per
//    mutation type the proposals, acceptances and rate.
// 2. Equal time: a BDPT reference with ref-spp samples per pixel (default 4096), then K runs (default 3,
//    different seeds) of bdpt, pssmlt and mmlt with a budget of S seconds each (default 10, seeding
//    included) on `threads` threads (default 1), and their relative mean squared error against the
//    reference: the mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2), also without the worst
//    0.1% of the pixels. Prints figures only; it never passes or fails.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "test_pssmlt_common.h"

namespace {

struct Options {
    int res = 64, mpp = 64, refSpp = 4096, runs = 3, threads = 1;
    double seconds = 10;
    std::string scene = "veach-bidir";
};

double secondsSince(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void throughput(const pf::Scene &scene, const pf::ChainIntegrator &integrator, int64_t mpp) {
    auto start = std::chrono::steady_clock::now();
    std::vector<pf::SeedingResult> seeds;
    for (const pf::SeedingTask &t : integrator.seedingTasks(scene))
        seeds.push_back(integrator.runSeeding(scene, 0, 1, t));
    const pf::Normalizer normalizer(std::move(seeds));
    const double seeding = secondsSince(start);
    pf::ChainImage image(pf::makeFilmBlock(scene));
    start = std::chrono::steady_clock::now();
    const double cpuStart = bench::processCpuSeconds();
    for (uint64_t i = 0; i < integrator.chainTaskCount(scene, mpp); ++i)
        pf::mergeChainResult(
            image, pf::runChainTask(scene, integrator, 1, integrator.chainTask(scene, normalizer, 1, mpp, i)));
    const double chains = secondsSince(start), cpu = bench::processCpuSeconds() - cpuStart;
    std::printf(
        "%s: seeding %.2f s (b = %.5g); %llu mutations in %.2f s on one core: %.4g mutations/s, %.4g per CPU "
        "second\n",
        integrator.name().c_str(), seeding, normalizer.luminance(), static_cast<unsigned long long>(image.mutations),
        chains, static_cast<double>(image.mutations) / chains, static_cast<double>(image.mutations) / cpu);
    std::printf("  %-10s %12s %12s %11s\n", "mutation", "proposed", "accepted", "acceptance");
    for (const pf::MutationCount &c : image.counts)
        std::printf("  %-10s %12llu %12llu %10.2f%%\n", c.name.c_str(), static_cast<unsigned long long>(c.proposed),
                    static_cast<unsigned long long>(c.accepted),
                    c.proposed ? 100.0 * static_cast<double>(c.accepted) / static_cast<double>(c.proposed) : 0.0);
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
        else if (a == "--threads" && value)
            o.threads = std::stoi(argv[++i]);
        else if (a == "--ref-spp" && value)
            o.refSpp = std::stoi(argv[++i]);
        else if (a == "--time" && value)
            o.seconds = std::stod(argv[++i]);
        else if (a == "--runs" && value)
            o.runs = std::stoi(argv[++i]);
        else
            o.scene = a;
    }
    const auto scene = pf::test::loadChainTestScene(o.scene, o.res);
    std::printf("%s, %d x %d, box filter\n", o.scene.c_str(), o.res, o.res);
    for (const std::string type : {"pssmlt", "mmlt"})
        throughput(*scene, dynamic_cast<const pf::ChainIntegrator &>(*pf::test::makeTestIntegrator(*scene, type, {})),
                   o.mpp);

    pf::RenderStats refStats;
    const auto bdpt = pf::test::makeTestIntegrator(*scene, "bdpt", {});
    const pf::Bitmap reference =
        bench::renderWith(*scene, *bdpt, o.refSpp, 0, 1000,
                          static_cast<int>(std::max(1u, std::thread::hardware_concurrency())), refStats);
    std::printf("reference: bdpt, %d spp, %.1f s\n", o.refSpp, refStats.seconds);
    std::printf("%-7s %4s %9s %9s %12s %16s\n", "", "run", "seconds", "spp/mpp", "relMSE", "w/o worst 0.1%");
    for (const std::string type : {"bdpt", "pssmlt", "mmlt"}) {
        const auto integrator = pf::test::makeTestIntegrator(*scene, type, {});
        bench::RelativeError mean;
        for (int run = 0; run < o.runs; ++run) {
            pf::RenderStats stats;
            const pf::Bitmap image =
                bench::renderWith(*scene, *integrator, 0, o.seconds, static_cast<uint64_t>(run + 1), o.threads, stats);
            const bench::RelativeError e = bench::relativeError(image, reference);
            mean.all += e.all / o.runs;
            mean.trimmed += e.trimmed / o.runs;
            std::printf("%-7s %4d %9.2f %9lld %12.4g %16.4g\n", type.c_str(), run, stats.seconds,
                        static_cast<long long>(stats.samplesPerPixel), e.all, e.trimmed);
        }
        std::printf("%-7s mean relMSE %.4g (without the worst 0.1%%: %.4g)\n", type.c_str(), mean.all, mean.trimmed);
    }
    return 0;
}
