// The warps' cost (core/warp.h): nanoseconds per call on one core, measured two ways. Independent calls on
// precomputed uniform numbers give the throughput a compiler and processor reach when calls overlap; a
// dependent chain, where each call's input waits for the previous result (as a path's next bounce waits
// for its direction), gives the latency that a path tracer's profile shows (issue 17).
//
//   bench_warp [--calls N]
//
// Prints figures only; it never passes or fails.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/rng.h"
#include "core/warp.h"

namespace {

using Clock = std::chrono::steady_clock;

double sum(const pf::Vec3 &v) { return v.x + v.y + v.z; }
double sum(const pf::Vec2 &v) { return v.x + v.y; }

struct Warp {
    const char *name;
    // One call; returns the sum of the result's coordinates, which the chain feeds into the next input (so
    // that the chain waits for every coordinate).
    double (*call)(const pf::Vec2 &u);
};

const Warp kWarps[] = {
    {"squareToCosineHemisphere", [](const pf::Vec2 &u) { return sum(pf::warp::squareToCosineHemisphere(u)); }},
    {"squareToUniformDiskConcentric",
     [](const pf::Vec2 &u) { return sum(pf::warp::squareToUniformDiskConcentric(u)); }},
    {"squareToUniformSphere", [](const pf::Vec2 &u) { return sum(pf::warp::squareToUniformSphere(u)); }},
    {"squareToUniformHemisphere", [](const pf::Vec2 &u) { return sum(pf::warp::squareToUniformHemisphere(u)); }},
    {"squareToUniformTriangle", [](const pf::Vec2 &u) { return sum(pf::warp::squareToUniformTriangle(u)); }},
    {"squareToStdNormal", [](const pf::Vec2 &u) { return sum(pf::warp::squareToStdNormal(u)); }},
};

double nanosecondsSince(Clock::time_point start, size_t calls) {
    return std::chrono::duration<double, std::nano>(Clock::now() - start).count() / static_cast<double>(calls);
}

}  // namespace

int main(int argc, char **argv) {
    size_t calls = 20'000'000;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--calls" && i + 1 < argc) {
            calls = std::strtoull(argv[++i], nullptr, 10);
        } else {
            std::fprintf(stderr, "usage: bench_warp [--calls N]\n");
            return 2;
        }
    }
    // A table of uniform pairs that fits in the L1 and L2 caches, reused cyclically.
    constexpr size_t kTable = 1 << 14;
    std::vector<pf::Vec2> u(kTable);
    pf::PCG32 rng(17, 3);
    for (pf::Vec2 &v : u) v = pf::Vec2(rng.nextDouble(), rng.nextDouble());

    std::printf("%-32s %14s %14s\n", "warp", "independent ns", "dependent ns");
    double checksum = 0;
    for (const Warp &w : kWarps) {
        auto start = Clock::now();
        double sum = 0;
        for (size_t k = 0; k < calls; ++k) sum += w.call(u[k & (kTable - 1)]);
        const double independent = nanosecondsSince(start, calls);
        // The previous result enters the next input below half an ulp of it: the number does not change,
        // but the processor cannot start the call before the previous one has finished.
        start = Clock::now();
        double link = 0;
        for (size_t k = 0; k < calls; ++k) {
            const pf::Vec2 &v = u[k & (kTable - 1)];
            link = w.call(pf::Vec2(v.x + link * link * 0x1p-80, v.y));
        }
        const double dependent = nanosecondsSince(start, calls);
        checksum += sum + link;
        std::printf("%-32s %14.2f %14.2f\n", w.name, independent, dependent);
    }
    std::printf("(checksum %g)\n", checksum);
    return 0;
}
