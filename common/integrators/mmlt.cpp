#include "integrators/mmlt.h"

#include <algorithm>

#include "scene/scene.h"

namespace pf {

namespace {

// Mutations per chain. A chain stays at its seed's depth, so each depth's share of the image is only as
// good as the number of chains resampled into it; pbrt-v3 runs 1000 chains for the same reason.
constexpr uint64_t kMutationsPerChain = 64;

}  // namespace

uint64_t MMLT::chainsPerTask(const Scene &scene) const {
    return std::max<uint64_t>(1, taskMutations(scene) / kMutationsPerChain);
}

PrimarySampleIntegrator::ChainSetup MMLT::setup(const Scene &scene, const ChainTask &task, const ChainSeed &seed,
                                                const Vec2 &raster, PCG32 &rng) const {
    const Film &film = scene.sensor().film();
    const Vec2 size(film.cropWidth(), film.cropHeight());
    const int depth = seed.record.s + seed.record.t - 1, strategies = depth + 2;
    ChainSetup s;
    s.psi = [this, &scene, size, depth, strategies](Sampler &u, SplatList &out) {
        const Vec2 unit = u.next2D(), position(unit.x * size.x, unit.y * size.y);
        const int lightVertices = std::min(static_cast<int>(u.next1D() * strategies), strategies - 1);
        bdpt().evaluate(
            scene, u, position,
            [&](const StrategySample &x) {
                // A chain of s + t = depth + 1 still leaves the paths whose crossings keep them within
                // the direct component's depth to that component.
                if (x.depth >= minDepth()) out.push_back({x.raster, x.value * strategies});
            },
            Strategy(lightVertices, depth + 1 - lightVertices));
    };
    // The strategy coordinate of the start is uniform within the seed's strategy cell, which makes the
    // seeding pool properly weighted for the multiplexed target (ALGORITHMS.md §2.4).
    s.prefix = {raster.x / size.x, raster.y / size.y, (seed.record.s + rng.nextDouble()) / strategies};
    s.normalization = task.depthLuminance[static_cast<size_t>(depth)];
    return s;
}

}  // namespace pf
