#include "integrators/lambda_tuning.h"

#include <algorithm>
#include <cmath>

#include "integrators/pilot_chains.h"
#include "path/path_chain.h"
#include "scene/scene.h"

namespace pf {

namespace {

constexpr uint64_t kTuneStream = 0x7a4eULL;
constexpr int kChains = 16, kBatches = 24;
constexpr uint64_t kBatchSteps = 50;
constexpr double kMinLambda = 1, kMaxLambda = 1e5;

}  // namespace

double tuneLambda(const Scene &scene, const PathSpaceIntegrator &integrator, uint64_t pilotSeed,
                  const std::vector<SeedCandidate> &pool) {
    if (!integrator.usesManifoldPerturbation()) return integrator.lambda();
    const std::vector<MutablePath> starts = pilotChainStarts(scene, integrator, pilotSeed, pool, kTuneStream, kChains);
    if (starts.empty()) return integrator.lambda();

    const std::string manifold = mutationName(MutationType::Manifold);
    ImageBlock nowhere(0, 0, 1, 1, nullptr);  // the chains' deposits are not wanted
    PCG32 rng(pilotSeed, kTuneStream);
    double logLambda = std::log(integrator.lambda());
    std::vector<double> history;  // log λ after each update
    for (MutablePath path : starts) {
        for (int b = 0; b < kBatches && path.length() > 0; ++b) {
            const MutationSet set = integrator.mutations(scene, {std::exp(logLambda), 0});
            PathChain chain(scene, set, integrator.minVertices(), integrator.maxVertices(), nowhere, 0.0);
            if (!(chain.start(path) > 0)) break;
            MutationCounts counts = integrator.mutationTypes();
            runMetropolis(chain, kBatchSteps, rng, nullptr, counts);
            path = chain.current();
            for (const MutationCount &c : counts)
                if (c.name == manifold && c.proposed > 0) {
                    const double acceptance = static_cast<double>(c.accepted) / static_cast<double>(c.proposed);
                    const double step = std::pow(static_cast<double>(history.size() + 1), -0.6);
                    logLambda -= step * (acceptance - kLambdaTargetAcceptance);
                    logLambda = std::clamp(logLambda, std::log(kMinLambda), std::log(kMaxLambda));
                    history.push_back(logLambda);
                }
        }
    }
    if (history.empty()) return integrator.lambda();
    // The mean over the second half of the updates (Polyak averaging), once the steps have shrunk.
    double sum = 0;
    const size_t half = history.size() / 2;
    for (size_t i = half; i < history.size(); ++i) sum += history[i];
    return std::exp(sum / static_cast<double>(history.size() - half));
}

}  // namespace pf
