// Veach's multi-chain perturbation (Veach & Guibas 1997; Veach 1997 ch. 11; ALGORITHMS.md §4.1-4.2):
// for paths whose camera side crosses several specular chains before an edge with two non-specular ends
// (the swimming pool, ...DS+DS+E), a lens perturbation of the first chain followed by a cascade: at each
// further non-specular vertex the direction towards the next chain is perturbed by an angle with density
// proportional to 1 / theta, and traced through that chain, until the new x_b connects to the unchanged
// x_{b-1}. T is the product of the per-chain densities, each converted to area at the next non-specular
// vertex. The angles range over [r1, r2] pixels' worth of the camera's angle per pixel, the lens
// perturbation's step sizes seen as angles.
#pragma once
#include "path/perturbation.h"

namespace pf {

class MultiChainPerturbation final : public Mutation {
public:
    explicit MultiChainPerturbation(const PerturbationScale &scale);
    MutationType type() const override { return MutationType::MultiChain; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;

private:
    PerturbationScale scale_;
    ReciprocalKernel offset_, angle_;
};

}  // namespace pf
