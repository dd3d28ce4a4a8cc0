#include "path/multichain_perturbation.h"

namespace pf {

MultiChainPerturbation::MultiChainPerturbation(const PerturbationScale &scale)
    : scale_(scale),
      offset_(scale.r1, scale.r2),
      angle_(scale.r1 * scale.radiansPerPixel, scale.r2 * scale.radiansPerPixel) {}

bool MultiChainPerturbation::applies(const PathView &x) const { return sensorChains(x).chains >= 2; }

bool MultiChainPerturbation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                    MutationRecord &record) const {
    const SensorChains chains = sensorChains(x);
    record = {chains.b - 1, x.length(), x.length() - chains.b};
    return sampleSensorCascade(scene, sampler, offset_, &angle_, x, chains, y);
}

double MultiChainPerturbation::density(const Scene &scene, const PathView &x, const PathView &y,
                                       const MutationRecord &) const {
    return sensorCascadeDensity(scene, offset_, &angle_, scale_, x, y);
}

}  // namespace pf
