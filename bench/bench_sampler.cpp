// The pixel samplers' cost: numbers per second on one core for the independent PCG32 streams and the
// low-discrepancy samplers (core/ld_sampler.h, and core/global_sobol_sampler.h on a 4096² film), drawn the way image
// tasks draw them: `spp` samples of each pixel in a row (a farm task or an `--spp` render: the per-pixel seeds are
// computed once per pixel), or one sample per pixel and pass (a `--time` render's passes: every sample starts a new
// pixel), with a path tracer's request pattern per sample (a 2D pixel position, then per bounce a 1D and two 2D
// requests).
//
//   bench_sampler [--spp N] [--bounces B] [--seconds S]
//
// Prints figures only; it never passes or fails.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/global_sobol_sampler.h"
#include "core/ld_sampler.h"

namespace {

struct Options {
    int spp = 16, bounces = 4;
    double seconds = 1;
};

// Runs the request pattern over pixels for about `seconds`; returns numbers per second and a checksum
// (which keeps the compiler from dropping the work).
std::pair<double, double> measure(pf::PixelSampler &sampler, const Options &opt, bool passes) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    double sum = 0, elapsed = 0;
    uint64_t numbers = 0, pixel = 0;
    const int perSample = 2 + opt.bounces * 5;
    while (elapsed < opt.seconds) {
        for (int k = 0; k < 4096; ++k, ++pixel)
            for (int s = 0; s < (passes ? 1 : opt.spp); ++s) {
                sampler.start(1, passes ? pixel % 65536 : pixel, passes ? pixel / 65536 : static_cast<uint64_t>(s));
                const pf::Vec2 p = sampler.next2D();
                sum += p.x + p.y;
                for (int b = 0; b < opt.bounces; ++b) {
                    const pf::Vec2 u = sampler.next2D(), v = sampler.next2D();
                    sum += sampler.next1D() + u.x + u.y + v.x + v.y;
                }
                numbers += perSample;
            }
        elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    }
    return {static_cast<double>(numbers) / elapsed, sum};
}

}  // namespace

int main(int argc, char **argv) {
    Options opt;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--spp" && i + 1 < argc)
            opt.spp = std::atoi(argv[++i]);
        else if (a == "--bounces" && i + 1 < argc)
            opt.bounces = std::atoi(argv[++i]);
        else if (a == "--seconds" && i + 1 < argc)
            opt.seconds = std::atof(argv[++i]);
        else {
            std::fprintf(stderr, "usage: bench_sampler [--spp N] [--bounces B] [--seconds S]\n");
            return 2;
        }
    }
    std::printf("numbers per second on one core, %d requests per sample (%d bounces)\n", 1 + 3 * opt.bounces,
                opt.bounces);
    pf::IndependentSampler independent;
    pf::LowDiscrepancySampler sobol, ldsampler(4);
    pf::GlobalSobolSampler global(4096, 4096);
    for (const auto &[name, sampler] : {std::pair<const char *, pf::PixelSampler *>{"independent", &independent},
                                        {"sobol (every request)", &sobol},
                                        {"ldsampler (dimension 4)", &ldsampler},
                                        {"sobol, layout image", &global}}) {
        const auto [tasks, a] = measure(*sampler, opt, false);
        const auto [passes, b] = measure(*sampler, opt, true);
        std::printf("  %-24s %6.1f M/s at %d spp per pixel, %6.1f M/s at one per pass   (checksum %.3g)\n", name,
                    tasks * 1e-6, opt.spp, passes * 1e-6, a + b);
    }
    return 0;
}
