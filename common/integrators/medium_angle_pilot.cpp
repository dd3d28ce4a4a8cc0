#include "integrators/medium_angle_pilot.h"

#include <algorithm>
#include <cmath>

#include "integrators/pilot_chains.h"
#include "path/path_chain.h"
#include "scene/scene.h"

namespace pf {

namespace {

constexpr uint64_t kAngleStream = 0xd7e7aULL;
constexpr int kChains = 16;
constexpr uint64_t kSteps = 400;
// Angles that differ by less are the same angle recomputed (float positions): a vertex the move kept.
constexpr double kUnchanged = 1e-6;

// The scattering angle at medium vertex i: between the directions of travel into it and out of it.
double scatteringAngle(const PathView &x, int i) {
    const Vec3 in = normalize(x.vertex(i).position() - x.vertex(i - 1).position());
    const Vec3 out = normalize(x.vertex(i + 1).position() - x.vertex(i).position());
    return std::acos(std::clamp(dot(in, out), -1.0, 1.0));
}

}  // namespace

MediumAnglePilot pilotMediumAngle(const Scene &scene, const PathSpaceIntegrator &integrator, uint64_t pilotSeed,
                                  const std::vector<SeedCandidate> &pool, double lambda) {
    MediumAnglePilot result{integrator.mediumAngle(), 0};
    if (!integrator.usesManifoldPerturbation()) return result;
    const std::vector<MutablePath> starts = pilotChainStarts(scene, integrator, pilotSeed, pool, kAngleStream, kChains);
    const std::string manifold = mutationName(MutationType::Manifold);
    const MutationSet set = integrator.mutations(scene, {lambda, 0});
    ImageBlock nowhere(0, 0, 1, 1, nullptr);  // the chains' deposits are not wanted
    PCG32 rng(pilotSeed, kAngleStream);
    std::vector<double> changes;
    for (const MutablePath &start : starts) {
        PathChain chain(scene, set, integrator.minVertices(), integrator.maxVertices(), nowhere, 0.0);
        if (!(start.length() > 0) || !(chain.start(start) > 0)) continue;
        MutationCounts counts = integrator.mutationTypes();
        const auto accepted = [&] {
            for (const MutationCount &c : counts)
                if (c.name == manifold) return c.accepted;
            return uint64_t(0);
        };
        for (uint64_t step = 0; step < kSteps; ++step) {
            const MutablePath x = chain.current();
            const uint64_t before = accepted();
            runMetropolis(chain, 1, rng, nullptr, counts);
            const MutablePath &y = chain.current();
            if (accepted() == before || y.length() != x.length()) continue;
            for (int i = 1; i + 1 < x.length(); ++i) {
                if (x.vertex(i).type != VertexType::Medium || y.vertex(i).type != VertexType::Medium) continue;
                const double change = std::abs(scatteringAngle(y, i) - scatteringAngle(x, i));
                if (change > kUnchanged) changes.push_back(change);
            }
        }
    }
    result.changes = changes.size();
    if (changes.empty()) return result;
    std::nth_element(changes.begin(), changes.begin() + static_cast<std::ptrdiff_t>(changes.size() / 2), changes.end());
    result.angle = changes[changes.size() / 2];
    return result;
}

}  // namespace pf
