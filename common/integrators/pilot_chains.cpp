#include "integrators/pilot_chains.h"

#include "render/normalizer.h"

namespace pf {

std::vector<MutablePath> pilotChainStarts(const Scene &scene, const PathSpaceIntegrator &integrator, uint64_t pilotSeed,
                                          const std::vector<SeedCandidate> &pool, uint64_t stream, uint64_t count) {
    SeedingResult all;
    all.candidates = pool;
    for (const SeedCandidate &c : pool) {
        if (all.depthLuminance.empty()) all.depthLuminance.push_back(0);
        all.depthLuminance[0] += c.weight;
    }
    std::vector<SeedingResult> results;
    results.push_back(std::move(all));
    const Normalizer normalizer(std::move(results));
    std::vector<MutablePath> starts;
    for (const ChainSeed &start : normalizer.resample(pilotSeed, stream, count)) {
        MutablePath path;
        integrator.bdpt().regenerate(scene, pilotSeed, start.record,
                                     [&](const StrategySample &x) { path = MutablePath(*x.path); });
        starts.push_back(std::move(path));
    }
    return starts;
}

}  // namespace pf
