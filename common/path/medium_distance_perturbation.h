// The medium-distance perturbation ([TH A4] and Mitsuba's manifold exploration, ALGORITHMS.md §6.7: "a
// perturbation of medium edge lengths; its density must enter T"): moves a medium vertex x_i along the edge from
// one of its neighbours, the anchor x_j (j = i ± 1), keeping the edge's direction, to the distance t' = t e^{±r}
// (t the current distance, r from Veach's 1/r kernel, the sign by a fair coin), and reconnects x_i to its other
// neighbour x_k. The manifold perturbation keeps medium distances fixed (its chains hold the segment lengths), so
// this is the move that changes them.
//
// Sources are the (x_i, x_j) with x_i a medium vertex and a junction x_i x_k (a connection can end at x_k;
// path/mutation.h). The edge x_j x_i may cross index-matched boundaries (the null BSDF, edge.h): they do not bend
// it, so x'_i stays on its line, and it lies in the medium beyond the last boundary that x_j x'_i crosses (which
// can be another medium than x_i's: the move then carries x_i across the boundary). A proposal is kept only if no
// other surface lies on x_j x'_i, so the support is symmetric, and every vertex but x_i stays.
//
// The density. Measured from the anchor, x_i has the coordinates (ω, t): direction and distance, with the volume
// element dV = t² dω dt. The move keeps ω (a Dirac delta in ω, the same in both directions, which cancels in the
// Metropolis-Hastings ratio) and draws t' with density q(t' | t) = p_r(|ln(t'/t)|) / (2 t'). In the volume
// measure of the path space (the canonical measure at a medium vertex), it is
//     T(x -> y) = 1 / |sources(x)| · q(t' | t) / t'²,
// so that f(y) T(y -> x) / (f(x) T(x -> y)) = f(y) t'² q(t | t') / (f(x) t² q(t' | t)) is the ratio in the
// coordinates (ω, t), in which the target density is f t².
#pragma once
#include <vector>

#include "path/perturbation.h"

namespace pf {

class MediumDistancePerturbation final : public Mutation {
public:
    MediumDistancePerturbation();
    MutationType type() const override { return MutationType::MediumDistance; }
    bool applies(const PathView &x) const override { return !sources(x).empty(); }
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;

    // A medium vertex and the neighbour it moves away from or towards.
    struct Source {
        int vertex = 0, anchor = 0;
    };
    // The sources of x, in a fixed order.
    std::vector<Source> sources(const PathView &x) const;
    // r = |ln(t'/t)|: Veach's 1/r kernel on [0.01, 1] (steps from 1% of the distance to a factor e).
    const ReciprocalKernel &kernel() const { return kernel_; }

private:
    ReciprocalKernel kernel_;
};

}  // namespace pf
