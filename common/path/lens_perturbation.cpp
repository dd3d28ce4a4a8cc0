#include "path/lens_perturbation.h"

namespace pf {

LensPerturbation::LensPerturbation(const PerturbationScale &scale) : scale_(scale), offset_(scale.r1, scale.r2) {}

bool LensPerturbation::applies(const PathView &x) const { return sensorChains(x).chains == 1; }

bool LensPerturbation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                              MutationRecord &record) const {
    const SensorChains chains = sensorChains(x);
    record = {chains.b - 1, x.length(), x.length() - chains.b};
    return sampleSensorCascade(scene, sampler, offset_, nullptr, x, chains, y);
}

double LensPerturbation::density(const Scene &scene, const PathView &x, const PathView &y,
                                 const MutationRecord &) const {
    return sensorCascadeDensity(scene, offset_, nullptr, scale_, x, y);
}

}  // namespace pf
