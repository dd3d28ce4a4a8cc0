// Bidirectional path tracing on a scene (default: the shared veach-bidir): throughput, and the error of
// BDPT and of the path tracer at equal time (Veach 1997 §10.6: BDPT's case is light reaching the scene
// through a glass-covered lamp).
//
//   bench_bdpt [--res N] [--spp N] [--threads N] [--ref-res N] [--ref-spp N] [--time S] [--runs K] [--out DIR]
//              [scene.xml]
//
// 1. Throughput: samples/s and rays/s of `bdpt` (and of `path`, for scale) at N x N (default 512), scene
//    load and BVH build excluded.
// 2. Equal time at ref-res x ref-res (default 128): a reference rendered by BDPT with ref-spp samples per
//    pixel (default 1024), then K runs (default 3, different seeds) of BDPT and of the path tracer with S
//    seconds each (default 10, spent in whole passes), and their relative mean squared error against the
//    reference,
//        relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2),
//    with the ratio of the means, relMSE(path) / relMSE(bdpt): BDPT's efficiency gain at equal time.
//    Paths that only one strategy samples (a small light seen through glass: s = 0 alone) make relMSE
//    heavy-tailed, a single pixel can hold most of it, so the same figures without the worst 0.1% of
//    the pixels are printed beside them. The reference's own error, which adds to both, is reported.
//    Both integrators use the scene file's maxDepth (and strictNormals for the path tracer). --out
//    writes the reference and the first run's images there as EXR. Prints figures only; it never
//    passes or fails.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "image/bitmap.h"
#include "image/film.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace {

struct Options {
    int res = 512, spp = 4, threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    int refRes = 128, refSpp = 1024, runs = 3;
    double seconds = 10;
    std::string scene = "scenes/veach-bidir/scene.xml", out;
};

pf::Bitmap render(const pf::Scene &scene, const std::string &type, const Options &o, int64_t spp, double seconds,
                  uint64_t seed, pf::RenderStats &stats) {
    const auto integrator = pf::createIntegrator(type, scene.integratorProperties(), false);
    pf::RenderOptions opt;
    opt.spp = spp;
    opt.timeLimit = seconds;
    opt.seed = seed;
    opt.threads = o.threads;
    return integrator->render(scene, opt, stats);
}

}  // namespace

int main(int argc, char **argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool hasValue = i + 1 < argc;
        if (a == "--res" && hasValue)
            o.res = std::stoi(argv[++i]);
        else if (a == "--spp" && hasValue)
            o.spp = std::stoi(argv[++i]);
        else if (a == "--threads" && hasValue)
            o.threads = std::stoi(argv[++i]);
        else if (a == "--ref-res" && hasValue)
            o.refRes = std::stoi(argv[++i]);
        else if (a == "--ref-spp" && hasValue)
            o.refSpp = std::stoi(argv[++i]);
        else if (a == "--time" && hasValue)
            o.seconds = std::stod(argv[++i]);
        else if (a == "--runs" && hasValue)
            o.runs = std::stoi(argv[++i]);
        else if (a == "--out" && hasValue)
            o.out = argv[++i];
        else
            o.scene = a;
    }
    auto scene = pf::loadScene(o.scene);
    std::printf("%s, %d threads\n", o.scene.c_str(), o.threads);

    scene->resizeFilm(o.res, o.res);
    std::printf("%-6s %5s %5s %14s %14s %14s\n", "", "res", "spp", "samples/s", "rays/s", "rays/sample");
    for (const std::string type : {"bdpt", "path"}) {
        pf::RenderStats stats;
        render(*scene, type, o, o.spp, 0, 1, stats);
        std::printf("%-6s %5d %5d %14.4g %14.4g %14.3g\n", type.c_str(), o.res, o.spp,
                    static_cast<double>(stats.samples) / stats.seconds, static_cast<double>(stats.rays) / stats.seconds,
                    static_cast<double>(stats.rays) / static_cast<double>(stats.samples));
    }

    scene->resizeFilm(o.refRes, o.refRes);
    pf::RenderStats refStats;
    const pf::Bitmap reference = render(*scene, "bdpt", o, o.refSpp, 0, 1000, refStats);
    // The reference's own error, from a second independent half: relMSE of two references of half the
    // samples each is twice the error of one of them, four times that of the full reference.
    pf::RenderStats halfStats;
    const pf::Bitmap halfA = render(*scene, "bdpt", o, o.refSpp / 2, 0, 2000, halfStats);
    const pf::Bitmap halfB = render(*scene, "bdpt", o, o.refSpp / 2, 0, 3000, halfStats);
    std::printf("reference: bdpt, %d x %d, %d spp, %.1f s; its own relMSE about %.3g\n", o.refRes, o.refRes, o.refSpp,
                refStats.seconds, bench::relativeError(halfA, halfB).all / 4);
    if (!o.out.empty()) pf::writeEXR(o.out + "/reference.exr", reference);

    bench::RelativeError mean[2];
    std::printf("%-6s %4s %9s %7s %12s %16s\n", "", "run", "seconds", "spp", "relMSE", "w/o worst 0.1%");
    for (int k = 0; k < 2; ++k) {
        const std::string type = k == 0 ? "bdpt" : "path";
        for (int run = 0; run < o.runs; ++run) {
            pf::RenderStats stats;
            const pf::Bitmap image = render(*scene, type, o, 0, o.seconds, static_cast<uint64_t>(run + 1), stats);
            const bench::RelativeError e = bench::relativeError(image, reference);
            mean[k].all += e.all / o.runs;
            mean[k].trimmed += e.trimmed / o.runs;
            std::printf("%-6s %4d %9.2f %7lld %12.4g %16.4g\n", type.c_str(), run, stats.seconds,
                        static_cast<long long>(stats.samplesPerPixel), e.all, e.trimmed);
            if (run == 0 && !o.out.empty()) pf::writeEXR(o.out + "/" + type + ".exr", image);
        }
    }
    std::printf("equal-time relMSE ratio path / bdpt: %.3g (without the worst 0.1%% of pixels: %.3g)\n",
                mean[1].all / mean[0].all, mean[1].trimmed / mean[0].trimmed);
    return 0;
}
