// WalkManifold throughput and behaviour on a glass sphere (tests/scenes/manifold/glass_sphere.xml by default):
// chains from a point light through two refractions to the floor (a caustic), whose end is moved to a random
// floor point within a radius r of it, for several r. Per r, on one thread: walks/s (walk() calls only), the
// share of walks that converge, the mean and maximum Newton iterations of converged walks, the failure reasons,
// and the share of converged walks whose reverse walk does not return to the start, the counterpart of
// [TR Table 1]'s non-reversible walks. "Returns" means the first specular vertex comes back within 100 ε L: the
// walks stop within ε L of their targets and the chain's Jacobian amplifies that (returns land up to about
// 3 ε L away on this scene), while another branch of the manifold lies orders of magnitude further.
//
//   bench_manifold_walk [--walks N] [scene.xml]
//
// Prints figures only; it never passes or fails.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "bsdf/bsdf.h"
#include "core/rng.h"
#include "manifold/manifold_walk.h"
#include "manifold/specular_constraint.h"
#include "scene/scene.h"

namespace {

using namespace pf;

double uniform(PCG32 &rng, double lo, double hi) { return lo + (hi - lo) * rng.nextDouble(); }

// Traces from x1 along d through two refractions (any dielectric) to the next surface, and builds the chain. A
// non-zero tilt refracts about the normal plus that vector (a glossy path): the chain then keeps its offsets.
std::optional<std::vector<ManifoldVertex>> traceChain(const Scene &scene, const Vec3 &x1, Vec3 d, const Vec3 &tilt) {
    std::vector<Intersection> hits;
    Vec3 o = x1;
    for (int i = 0; i < 3; ++i) {
        Intersection its;
        if (!scene.intersect(Ray(o, d, scene.epsilonAt(o)), its)) return std::nullopt;
        hits.push_back(its);
        if (i == 2) break;
        const BSDF *bsdf = its.bsdf();
        if (!bsdf || !bsdf->hasDelta() || bsdf->eta() == 1.0) return std::nullopt;
        const bool outside = dot(-d, its.n) > 0;
        const std::optional<Vec3> wo = scatterAbout(-d, normalize(its.n + tilt), Scattering::Refraction,
                                                    outside ? bsdf->eta() : 1.0 / bsdf->eta());
        if (!wo) return std::nullopt;
        o = its.p;
        d = normalize(*wo);
    }
    std::vector<ManifoldVertex> chain = {ManifoldVertex::fixedPosition(x1)};
    for (int i = 0; i < 2; ++i) {
        const std::optional<ManifoldVertex> v =
            ManifoldVertex::constrained(hits[i], i == 0 ? x1 : hits[i - 1].p, hits[i + 1].p, tilt.isZero());
        if (!v) return std::nullopt;
        chain.push_back(*v);
    }
    const std::optional<ManifoldVertex> end = ManifoldVertex::surface(hits[2]);
    if (!end || hits[2].bsdf()->hasDelta()) return std::nullopt;
    chain.push_back(*end);
    return chain;
}

// One row of the table: `walks` walks of chains with microfacet tilts of up to tiltSize (0: ideal specular)
// whose end moves within ±radius.
void runRow(const Scene &scene, const ManifoldWalk &walker, double tiltSize, double radius, int walks) {
    PCG32 rng(42, static_cast<uint64_t>(radius * 1000));
    int done = 0, converged = 0, maxIterations = 0, nonReversible = 0;
    long iterations = 0;
    int byStatus[5] = {0, 0, 0, 0, 0};
    double seconds = 0;
    while (done < walks) {
        const Vec3 x1(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 4);
        const Vec3 aim(uniform(rng, -0.7, 0.7), uniform(rng, -0.7, 0.7), 0);
        const Vec3 tilt = Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)) * tiltSize;
        const std::optional<std::vector<ManifoldVertex>> chain = traceChain(scene, x1, normalize(aim - x1), tilt);
        if (!chain) continue;
        const Vec3 end = chain->back().p;
        Intersection its;
        const Vec3 from(end.x + uniform(rng, -radius, radius), end.y + uniform(rng, -radius, radius), end.z + 0.5);
        if (!scene.intersect(Ray(from, Vec3(0, 0, -1)), its)) continue;
        const std::optional<ManifoldVertex> target = ManifoldVertex::surface(its);
        if (!target) continue;
        const auto t0 = std::chrono::steady_clock::now();
        const WalkResult result = walker.walk(*chain, *target);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        ++done;
        ++byStatus[static_cast<int>(result.status)];
        if (!result.converged()) continue;
        ++converged;
        iterations += result.stats.iterations;
        maxIterations = std::max(maxIterations, result.stats.iterations);
        const WalkResult back = walker.walk(result.chain, chain->back());
        const double returnTolerance = 100 * walker.parameters().epsilon * walker.sceneScale();
        if (!back.converged() || (back.chain[1].p - (*chain)[1].p).length() > returnTolerance) ++nonReversible;
    }
    std::printf("%7s %8.3g %12.4g %9.2f%% %10.3f %8d %9.2f%% %9.3f%% %9.2f%% %11.3f%%\n",
                tiltSize > 0 ? "offset" : "ideal", radius, done / seconds, 100.0 * converged / done,
                converged ? double(iterations) / converged : 0.0, maxIterations,
                100.0 * byStatus[static_cast<int>(WalkStatus::IterationLimit)] / done,
                100.0 * byStatus[static_cast<int>(WalkStatus::SingularJacobian)] / done,
                100.0 * byStatus[static_cast<int>(WalkStatus::Occluded)] / done,
                converged ? 100.0 * nonReversible / converged : 0.0);
}

}  // namespace

int main(int argc, char **argv) {
    int walks = 20000;
    std::string path = "tests/scenes/manifold/glass_sphere.xml";
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--walks" && i + 1 < argc)
            walks = std::stoi(argv[++i]);
        else
            path = a;
    }
    const auto scene = loadScene(path);
    const ManifoldWalk walker(*scene);
    std::printf("scene %s, L = %.4g, eps L = %.3g\n", path.c_str(), walker.sceneScale(),
                walker.parameters().epsilon * walker.sceneScale());
    std::printf("%7s %8s %12s %10s %10s %8s %10s %10s %10s %12s\n", "chain", "radius", "walks/s", "converged",
                "mean it", "max it", "it.limit", "singular", "occluded", "non-revers.");
    for (const double tiltSize : {0.0, 0.1})
        for (const double radius : {0.01, 0.05, 0.2, 1.0, 3.0}) runRow(*scene, walker, tiltSize, radius, walks);
    return 0;
}
