// Veach's lens perturbation (Veach & Guibas 1997; Veach 1997 ch. 11; ALGORITHMS.md §4.1-4.2): for a
// path whose first non-specular vertex x_b seen from the camera is followed by another non-specular vertex
// (the form ...DD S* E), move the raster position by an image-plane offset with density proportional to
// 1 / r on [r1, r2], trace the new camera ray through the same specular chain to a new x_b, and connect it
// to the unchanged x_{b-1}. The offset kernel is symmetric, so T(x -> y) / T(y -> x) is the ratio of the
// image-plane-to-area Jacobians at the new and old x_b; this class computes both T in full.
#pragma once
#include "path/perturbation.h"

namespace pf {

class LensPerturbation final : public Mutation {
public:
    explicit LensPerturbation(const PerturbationScale &scale);
    MutationType type() const override { return MutationType::Lens; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;

private:
    PerturbationScale scale_;
    ReciprocalKernel offset_;
};

}  // namespace pf
