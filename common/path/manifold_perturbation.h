// The manifold perturbation of manifold exploration ([TR §5.1], [TH §6.1]; ALGORITHMS.md §6.5), ideal
// specular chains: it perturbs the direction leaving a non-specular vertex x_s with a von Mises-Fisher lobe,
// propagates it through the specular chain that follows to a new non-specular vertex x'_m, and reconnects
// x'_m to the next non-specular vertex x_f through the second specular chain with WalkManifold, keeping
// x_f fixed. It subsumes Veach's lens, caustic and multi-chain perturbations (ALGORITHMS.md §5.4).
//
// Strategies (§6.5): a non-specular vertex x_s and a direction (towards the light or the camera), uniformly
// over the pairs whose walk finds two more non-specular vertices x_m, x_f before running off the path (the
// restart of the seeds' sampling); the set depends only on the configuration, which the move keeps, so the
// probability is the same from x and from y. Each strategy is a reversible kernel of its own (its reverse
// move is the same strategy from y), which is why MutationRecord::source names it.
//
// Direction kernel: vMF around the current direction w_o with kappa such that the peak density is
// lambda^2 p(w_i -> w_o) (vmf.h), p the solid-angle density of x_s's own sampling (BSDF, emission or camera),
// clamped to at least 1/(4 pi) as in Mitsuba.
//
// Transition density. In the manifold measure ([TR §5.1])
//     T(x -> y) = D_x(w'_o) / |cos(n_s, w'_o)| G(x_s <-> ... <-> x'_m),
// with the kernel of the source state x and the cosine of the new direction. Chains use the canonical
// measure of path/mutation.h, whose density of a specular chain traced from a direction is that direction's
// solid-angle density times propagationJacobian(). Between two non-specular vertices u (sensor side) and l,
// the two measures differ by rho = G(u <-> ... <-> l) / (|cos_u| propagationJacobian(u -> l, sensor walk)):
// both are densities of the same traced vertex, per manifold and per canonical measure (§6.3); G here is the
// Jacobian seen from u (through refractions the two directions differ by the etendue's squared indices). Hence
//     T_canonical(x -> y) = D_x(w'_o) J_1(y) / rho_2(y),
// J_1 the first chain's propagation Jacobian (converted to the canonical measure where the emitter walk
// traced it, as in the caustic perturbation) and rho_2 the second chain's conversion (1 without specular
// vertices). G of the first chain cancels as [TR §5.1] notes; that of the second stays.
//
// Reversibility (§6.5, mandatory): a proposal is kept only if walking the second chain back from y to x's
// x_m converges to x's chain (its first walked vertex within a relative tolerance).
//
// Not done: glossy vertices on offset manifolds (§6.6; here every smooth vertex is non-specular, which keeps
// the method unbiased but loses its advantage on glossy chains), the endpoint position perturbation on
// lights and apertures, and chains whose moving vertex lies in a medium.
#pragma once
#include <vector>

#include "manifold/manifold_walk.h"
#include "manifold/vmf.h"
#include "path/mutation.h"

namespace pf {

class ManifoldPerturbation final : public Mutation {
public:
    ManifoldPerturbation(const Scene &scene, double lambda);
    MutationType type() const override { return MutationType::Manifold; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;
    // Table 1 (ALGORITHMS.md §5.5): walks, converged walks, Newton iterations, chain sizes, reverse walks
    // and non-reversible proposals.
    void addCounters(ChainCounters &counters) const override;

    // A strategy: the vertex whose direction is perturbed, the vertex that moves, the vertex that stays.
    struct Strategy {
        int source = 0, moving = 0, fixed = 0;
    };
    // The strategies of x, in a fixed order.
    static std::vector<Strategy> strategies(const PathView &x);
    // The direction kernel at x's vertex `source` towards `source + dir`.
    VonMisesFisher kernel(const Scene &scene, const PathView &x, int source, int dir) const;
    // rho of y's chain between non-specular vertices `end` and `moving` (either order): the manifold
    // measure's density of a vertex traced through the chain over the canonical one (see above); 0 when the
    // chain is degenerate.
    static double measureRatio(const PathView &y, int end, int moving);

private:
    // The statistics of one chain's run (a MutationSet is built per chain, so nothing is shared).
    struct Statistics {
        double walks = 0, converged = 0, iterations = 0, chainVertices = 0, maxChainVertices = 0;
        double reverseWalks = 0, nonReversible = 0;
    };
    // Reconnects y's new x_m to x_f through the second chain (x's specular vertices between them).
    bool connectChain(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                      const Strategy &st) const;

    double lambda_;
    ManifoldWalk walk_;
    mutable Statistics stats_;
};

}  // namespace pf
