// Per-sample quality apart from speed: the relative MSE of integrators at a fixed number of samples (or
// mutations) per pixel, averaged over seeds, against a reference (issue 20: pathfarm's error per sample
// next to Mitsuba 0.6's, before the speed of either enters; an equal-time ratio is then this ratio times
// the ratio of samples per second). With --time, the same at equal time (issue 17): every render gets S
// seconds of wall time and the samples (or mutations) it took are printed per pixel and per second and
// core, the figures to set beside a Mitsuba 0.6 render of the same file (scripts/mitsuba-equal-time.sh), and
// per second of the process's CPU time (bench::processCpuSeconds; comparable on a shared machine).
//
//   bench_per_sample [--res N] [--spp N | --time S] [--seeds K] [--integrators a,b,..] [--threads N]
//                    [--reference FILE.exr | --ref-spp N] [--block B] [--worst M] [--image NAME=FILE.exr]...
//                    [scene.xml]
//
// For each integrator (default bdpt,path) K renders (default 3; seeds 1..K) at N x N (default 64) with N
// spp (default 16) or S seconds, and for each
//     relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2)
// per pixel and over B x B block means (default 8; the measure of issue 20, which averages most of the
// pixel noise out and keeps systematic differences), with the mean over seeds and its standard error.
// Then the M blocks (default 4) holding most of the block error of the first integrator, with their mean
// luminance in its renders and in the reference and their share of the block error: a systematic
// difference (veach-bidir's wall lamp against Mitsuba) shows where it sits. The reference is an EXR of
// the same resolution (a long Mitsuba or pathfarm render) or, without --reference, a pathfarm BDPT render
// with --ref-spp samples per pixel (default 1024, seed 1000). Each --image (e.g. Mitsuba's render of the same
// file in the same time) is measured the same way, as one more row. Prints figures only; never passes or fails.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "image/bitmap.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace {

struct Options {
    int res = 64, spp = 16, seeds = 3, refSpp = 1024, block = 8, worst = 4;
    double time = 0;  // seconds per render; 0: spp per pixel
    int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    std::vector<std::string> integrators = {"bdpt", "path"};
    std::vector<std::pair<std::string, std::string>> images;  // name, EXR rendered elsewhere
    std::string scene = "scenes/veach-bidir/scene.xml", reference;
};

double luminance(const pf::Spectrum &s) { return 0.212671 * s.r + 0.715160 * s.g + 0.072169 * s.b; }

// Per block and channel, the mean of the block's pixels (blocks cut by the border are left out), in row order.
std::vector<pf::Spectrum> blockMeanList(const pf::Bitmap &img, int b) {
    const pf::Bitmap blocks = pf::blockMeans(img, b);
    std::vector<pf::Spectrum> means;
    for (int y = 0; y < blocks.height; ++y)
        for (int x = 0; x < blocks.width; ++x) means.push_back(blocks.get(x, y));
    return means;
}

// relMSE's term per block, summed over channels (the epsilon of pathfarm diff).
std::vector<double> blockErrors(const std::vector<pf::Spectrum> &a, const std::vector<pf::Spectrum> &r) {
    std::vector<double> e(a.size());
    for (size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) e[i] += (a[i][c] - r[i][c]) * (a[i][c] - r[i][c]) / (r[i][c] * r[i][c] + 1e-2);
    return e;
}

struct MeanError {
    double mean = 0, stderr_ = 0;
};
MeanError meanOf(const std::vector<double> &v) {
    MeanError m;
    m.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
    if (v.size() > 1) {
        double ss = 0;
        for (const double x : v) ss += (x - m.mean) * (x - m.mean);
        m.stderr_ = std::sqrt(ss / static_cast<double>(v.size() - 1) / static_cast<double>(v.size()));
    }
    return m;
}

pf::Bitmap render(const pf::Scene &scene, const std::string &type, int spp, double seconds, uint64_t seed, int threads,
                  pf::RenderStats &stats) {
    const auto integrator = pf::createIntegrator(type, scene.integratorProperties(), false);
    return bench::renderWith(scene, *integrator, spp, seconds, seed, threads, stats);
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
        else if (a == "--time" && hasValue)
            o.time = std::stod(argv[++i]);
        else if (a == "--seeds" && hasValue)
            o.seeds = std::max(1, std::stoi(argv[++i]));
        else if (a == "--ref-spp" && hasValue)
            o.refSpp = std::stoi(argv[++i]);
        else if (a == "--reference" && hasValue)
            o.reference = argv[++i];
        else if (a == "--block" && hasValue)
            o.block = std::max(1, std::stoi(argv[++i]));
        else if (a == "--worst" && hasValue)
            o.worst = std::stoi(argv[++i]);
        else if (a == "--image" && hasValue && std::string(argv[i + 1]).find('=') != std::string::npos) {
            const std::string v = argv[++i];
            o.images.emplace_back(v.substr(0, v.find('=')), v.substr(v.find('=') + 1));
        } else if (a == "--threads" && hasValue)
            o.threads = std::stoi(argv[++i]);
        else if (a == "--integrators" && hasValue) {
            o.integrators.clear();  // "" or "none": only the --image rows
            std::stringstream list(argv[++i]);
            for (std::string name; std::getline(list, name, ',');)
                if (!name.empty() && name != "none") o.integrators.push_back(name);
        } else
            o.scene = a;
    }
    if (o.integrators.empty() && o.images.empty()) {
        std::fprintf(stderr, "nothing to measure: give --integrators or --image\n");
        return 2;
    }
    auto scene = pf::loadScene(o.scene);
    scene->resizeFilm(o.res, o.res);
    pf::RenderStats refStats;
    const pf::Bitmap reference =
        o.reference.empty() ? render(*scene, "bdpt", o.refSpp, 0, 1000, o.threads, refStats) : pf::readEXR(o.reference);
    if (reference.width != o.res || reference.height != o.res) {
        std::fprintf(stderr, "the reference is %d x %d, the renders %d x %d\n", reference.width, reference.height,
                     o.res, o.res);
        return 2;
    }
    char budget[64];
    if (o.time > 0)
        std::snprintf(budget, sizeof budget, "%g s", o.time);
    else
        std::snprintf(budget, sizeof budget, "%d spp", o.spp);
    std::printf(
        "%s at %d x %d, %s, seeds 1..%d, %d threads; reference: %s\n", o.scene.c_str(), o.res, o.res, budget, o.seeds,
        o.threads,
        o.reference.empty() ? ("pathfarm bdpt, " + std::to_string(o.refSpp) + " spp").c_str() : o.reference.c_str());
    const std::vector<pf::Spectrum> refBlocks = blockMeanList(reference, o.block);
    // Samples: pixel samples, or mutations for the Markov-chain integrators (their RenderStats::samples).
    std::printf("%-8s %24s %24s %14s %16s %14s\n", "", "relMSE (pixels)",
                ("relMSE (" + std::to_string(o.block) + "^2 blocks)").c_str(), "samples/px", "samples/s/core",
                "samples/cpu-s");

    std::vector<double> worstErrors;       // first integrator: block error summed over seeds
    std::vector<pf::Spectrum> worstMeans;  // and its block means, averaged over seeds
    for (const std::string &type : o.integrators) {
        std::vector<double> pixel, block;
        double samples = 0, seconds = 0, cpuSeconds = 0;
        std::vector<double> sumErrors(refBlocks.size(), 0.0);
        std::vector<pf::Spectrum> sumMeans(refBlocks.size(), pf::Spectrum(0.0));
        for (int k = 1; k <= o.seeds; ++k) {
            pf::RenderStats stats;
            const double cpuStart = bench::processCpuSeconds();
            const pf::Bitmap image = render(*scene, type, o.spp, o.time, static_cast<uint64_t>(k), o.threads, stats);
            cpuSeconds += bench::processCpuSeconds() - cpuStart;
            samples += static_cast<double>(stats.samples);
            seconds += stats.seconds;
            pixel.push_back(bench::relativeError(image, reference).all);
            const std::vector<pf::Spectrum> means = blockMeanList(image, o.block);
            const std::vector<double> e = blockErrors(means, refBlocks);
            block.push_back(std::accumulate(e.begin(), e.end(), 0.0) / (3.0 * static_cast<double>(e.size())));
            for (size_t i = 0; i < e.size(); ++i) {
                sumErrors[i] += e[i];
                sumMeans[i] += means[i] / o.seeds;
            }
        }
        const MeanError p = meanOf(pixel), b = meanOf(block);
        std::printf("%-8s %12.4g +- %-9.2g %12.4g +- %-9.2g %14.4g %16.4g %14.4g\n", type.c_str(), p.mean, p.stderr_,
                    b.mean, b.stderr_, samples / (o.seeds * static_cast<double>(o.res) * o.res),
                    samples / std::max(seconds, 1e-9) / o.threads, samples / std::max(cpuSeconds, 1e-9));
        if (worstErrors.empty()) {
            worstErrors = sumErrors;
            worstMeans = sumMeans;
        }
    }

    for (const auto &[name, file] : o.images) {
        const pf::Bitmap image = pf::readEXR(file);
        if (image.width != o.res || image.height != o.res) {
            std::fprintf(stderr, "%s is %d x %d, the renders %d x %d\n", file.c_str(), image.width, image.height, o.res,
                         o.res);
            return 2;
        }
        const std::vector<pf::Spectrum> means = blockMeanList(image, o.block);
        const std::vector<double> e = blockErrors(means, refBlocks);
        if (worstErrors.empty()) {
            worstErrors = e;
            worstMeans = means;
        }
        std::printf("%-8s %12.4g %12s %12.4g %12s %14s %16s\n", name.c_str(),
                    bench::relativeError(image, reference).all, "",
                    std::accumulate(e.begin(), e.end(), 0.0) / (3.0 * static_cast<double>(e.size())), "", "-", "-");
    }

    // Where the first row's block error sits.
    std::vector<size_t> order(worstErrors.size());
    std::iota(order.begin(), order.end(), size_t(0));
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return worstErrors[a] > worstErrors[b]; });
    const double total = std::accumulate(worstErrors.begin(), worstErrors.end(), 0.0);
    const int perRow = o.res / o.block;
    std::printf("%s: blocks with most of the block error (x, y in blocks; mean luminance)\n",
                o.integrators.empty() ? o.images.front().first.c_str() : o.integrators.front().c_str());
    for (int i = 0; i < std::min<int>(o.worst, static_cast<int>(order.size())); ++i) {
        const size_t b = order[static_cast<size_t>(i)];
        std::printf("  (%3d, %3d)  image %10.4g  reference %10.4g  share %5.1f%%\n", static_cast<int>(b) % perRow,
                    static_cast<int>(b) / perRow, luminance(worstMeans[b]), luminance(refBlocks[b]),
                    total > 0 ? 100.0 * worstErrors[b] / total : 0.0);
    }
    return 0;
}
