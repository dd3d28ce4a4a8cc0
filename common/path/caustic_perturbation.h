// Veach's caustic perturbation (Veach & Guibas 1997; Veach 1997 ch. 11; ALGORITHMS.md §4.1-4.2): the
// lens perturbation run from the light side, for paths whose vertex x_{n-2} next to the camera is
// non-specular and is reached from the previous non-specular vertex x_a through a (possibly empty) chain of
// specular vertices (caustics seen directly, ...D S* D E). The direction leaving x_a is perturbed by an
// angle with density proportional to 1 / theta on [theta1, theta2] and traced through the same specular
// chain to a new x_{n-2}, which is connected to the camera. Veach scales the angles so that the motion on
// the image matches the lens perturbation's: the pixel angles [r1, r2] * (angle per pixel) times the
// length of the camera edge over the length of the light-side chain (so the range depends on the state,
// and T(y -> x) uses y's). The chain is traced by the emitter walk, so T is converted to the canonical
// measure (path/mutation.h).
#pragma once
#include "path/perturbation.h"

namespace pf {

class CausticPerturbation final : public Mutation {
public:
    explicit CausticPerturbation(const PerturbationScale &scale);
    MutationType type() const override { return MutationType::Caustic; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;

    // The kernel of the angle at x_a for a path x the perturbation applies to.
    ReciprocalKernel angleKernel(const PathView &x) const;

private:
    PerturbationScale scale_;
};

}  // namespace pf
