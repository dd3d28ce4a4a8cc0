// The manifold perturbation of manifold exploration ([TR §5.1-5.2], [TH §6.1-6.2]; ALGORITHMS.md §6.5-6.6) with
// the glossy extension: it perturbs the direction leaving a non-specular vertex x_a with a von Mises-Fisher lobe,
// propagates it through the chain that follows to a new vertex x'_b, and reconnects x'_b to the next
// non-specular vertex x_c through the second chain with WalkManifold, keeping x_c fixed. Chain vertices are
// ideal specular ones and glossy ones that this move treats as specular: those keep their offset o (the
// tangent projection of the normalized generalized half-vector, with its sign) and are scattered about the
// microfacet normal m(o) instead of the normal, in the propagation and in the walk (offset manifolds, §6.6).
// It subsumes Veach's lens, caustic and multi-chain perturbations (ALGORITHMS.md §5.4).
//
// Classification (§6.6, [TR A1] with the erratum). A glossy vertex (a microfacet conductor or dielectric; see
// chainProbability()) joins a chain with probability psi_spec = 1 - P_nonspec(theta_q(alpha), dtheta), ideal
// specular vertices always, medium vertices as below, and the others (diffuse, rough plastic, endpoints) never.
// Rough plastic stays out: its diffuse base scatters everywhere, and a psi of its specular lobe alone would
// treat a mostly diffuse vertex as specular. Glossy vertices on meshes and on analytic shapes alike: their
// offsets are measured in a tangent frame that depends on the shading normal alone, whose turn ∇C models
// (specular_constraint.h), so G_o and J below are exact on spheres as on triangles (checked against finite
// differences in test_detailed_balance on both). dtheta, the mean angle by which a perturbation turns a microfacet
// normal, is the integrators' `manifoldGlossyAngle` (default 1 degree, the value Mitsuba starts its pilot
// estimate from); 0 turns the extension off, leaving every glossy vertex non-specular.
//
// Strategy sampling. A source (x_a, direction towards the light or the camera) uniformly over the sources
// whose walk can find x_b (a surface) and x_c (a usable end) for some classification: the set depends only
// on the configuration. Then the vertices after x_a are classified one by one, in the walk's direction; the
// first non-specular one is x_b, the next x_c. A walk that runs off the path, or a classification that makes
// x_b or x_c unusable, is a failed proposal: restarting would make the probability of the chosen strategy
// depend on the state through the psi of the vertices that a failed walk crossed. The strategy's probability
//     P(st | x) = 1 / |sources(x)| P_nonspec(x_b) P_nonspec(x_c) prod_{a<i<c, i != b} psi_spec(x_i)
// is evaluated at the source state: the psi depend on roughness at the vertices' positions, so the two
// directions of a move do not cancel them ([TR eq. 12]). MutationRecord::moving keeps x_b, which, with
// source, fixes the classification of every vertex between x_a and x_c.
//
// The transition density. Let o be the offsets of the glossy chain vertices g_1 .. g_k. The move is
// deterministic given the sampled direction: propagation and walk keep o, and both directions of a move see
// the same o (y's offsets are x's). So, in coordinates (x_b, o) of the states with x's configuration, the
// proposal from x is T_M(x -> y) d x_b times a Dirac delta at o(x), and the reverse one has the same Dirac
// delta at o(y) = o(x): the deltas cancel in the Metropolis-Hastings ratio. What does not cancel is that the
// target density lives in the area measure of (x_b, g_1 .. g_k): in (x_b, o) it is f(x) J(x) with
//     J = |∂[x_b, x_g1 .. x_gk] / ∂[x_b, o_g1 .. o_gk]|   (manifold/offset_jacobian.h, x_a and x_c fixed).
// The ratio f(y) J(y) T_M(y -> x) / (f(x) J(x) T_M(x -> y)) is the MH ratio of
//     T(x -> y) = T_M(x -> y) / J(y),
// J at the destination, which is how density() reports it (equivalently T_M(x -> y) J(x), [TR eq. 12] with
// the factor at the source; the ratio is the same). T_M is the density of x'_b per unit area on x's offset
// manifold, through the first chain with its offsets held:
//     T_M(x -> y) = P(st | x) D_x(w'_o) / |cos(n_a, w'_o)| G_o(x_a <-> ... <-> x'_b),
// D_x the vMF lobe of the source state (kappa from lambda^2 p, p the solid-angle density of x_a's own
// sampling, clamped to at least 1/(4 pi) as in Mitsuba), the cosine of the new direction, and G_o the
// generalized geometry term through the chain as it is (glossy vertices constrained to their offsets; the
// Jacobian of the constraint does not depend on o, §6.6), seen from x_a. Without glossy vertices J = 1 and
// this is §6.5.
//
// The measure. Chains use the canonical measure of path/mutation.h, in which an ideal specular vertex counts
// with the pseudo-measure of the walk crossing it. Between two consecutive non-Dirac vertices u (sensor side)
// and l, the manifold and the canonical measure differ by
//     rho = G(u <-> ... <-> l) / (|cos_u| propagationJacobian(u -> l, sensor walk)):
// both are densities of the same traced vertex (§6.3), G seen from u (through refractions the two directions
// differ by the etendue's squared indices). f in the canonical measure is the manifold f over the product R
// of rho over y's ideal sub-chains between x_a and x_c (the sub-chains elsewhere do not change), so
//     T_canonical(x -> y) = T_M(x -> y) / (R(y) J(y)),
// which is what density() returns; measureConversion() is R J. Where the first chain is ideal specular,
// G / (|cos_a| R_first) is the propagation Jacobian of the traced chain in the canonical measure itself
// (perturbation.h), which density() uses there: the same number, but without G's ill-conditioning near a
// caustic fold (both agree to 1e-5 on the test scenes away from folds).
//
// Media: T_M also has the free-flight probabilities with which the traced edges were crossed (the walk's own
// edge densities; rho, built from the sensor walk's, is corrected to them where a medium vertex ends a
// sub-chain).
//
// Medium vertices in chains (§6.7, [TR §7]): a medium vertex joins a chain with probability
// psi_spec = 1 - P_nonspec(theta_q(g), dtheta), theta_q the median scattering angle of its Henyey-Greenstein phase
// function (g = its mean cosine) and dtheta the integrators' `manifoldMediumAngle` (by default the same
// `manifoldGlossyAngle` as for surfaces; Jakob measures a mean change of scattering angle in a pilot, which
// integrators/medium_angle_pilot.h does), unless `mediumChains` is false. It keeps its offset (the
// scattering direction in the frame of the incoming one) and its distance to its predecessor in the direction
// of the walk: propagation and the traced second chain place it at that held distance (placeHeld(), no
// free-flight sampling, so its incoming edge has no free-flight probability in T), and the walk holds it too.
// T then carries J with (o, ℓ) as held coordinates of each medium vertex, in the volume measure
// (manifold/offset_jacobian.h), and G_o through medium vertices (manifold/chain_jacobian.h's length rows).
//
// A medium vertex can also be x_b, the vertex that moves (§6.7: a medium vertex is non-specular like a diffuse
// one; the camera seeing a medium through glass, E S M .., has no other vertex whose move reaches the film): the
// first chain's propagation samples its new distance by free flight (so T has that edge's free-flight density,
// per unit length, and x'_b's density is per unit volume), and the second chain's walk aims at it on the plane
// facing its neighbour (a MediumEndpoint target, manifold_walk.h) and places it there (no free-flight density on
// that edge). Only with ideal specular chains on both sides: the offset Jacobian holds surface x_b only.
//
// Reversibility (§6.5, mandatory): a proposal is kept only if walking the second chain back from y to x's
// x_b converges to x's chain (its first walked vertex within a relative tolerance).
//
// Endpoint position perturbation (§6.5). The supernodes are sources too: their move offsets the position of
// the light or aperture node x_b after them by a tangential Gaussian (positionKernel()), and x_b is
// reconnected to x_c as above (a junction or a walk; on the aperture only a junction, since a chain seen
// through the lens would have to land on the lens plane). T is then the Gaussian's area density in place of
// T_M's direction lobe and first chain. Only planar lights and apertures are moved: the new point must lie
// in x_b's plane with x_b's normal (the offset is then the area measure's own coordinate, and the kernel is
// symmetric); on a curved light the move fails. This explores soft shadows and depth of field.
//
// Index-matched boundaries (the null BSDF, edge.h) may lie on any edge of a chain: the walk passes straight through
// them (manifold_walk.h), and a held medium vertex beyond one lies in the medium on its far side (placeHeld()). They
// bend no ray, so C, G_o and J are those of the chain without them; the traced edges carry their transmittance
// through both media and the free-flight probabilities of every medium segment, which T_M and rho use as above.
#pragma once
#include <vector>

#include "manifold/manifold_walk.h"
#include "manifold/vmf.h"
#include "path/mutation.h"

namespace pf {

class ManifoldPerturbation final : public Mutation {
public:
    // lambda: the jump size (§6.5); glossyAngle: dtheta of the classification in radians (0: no glossy or medium
    // vertex joins a chain); mediumChains: whether medium vertices may join chains (§6.7); mediumAngle: dtheta of
    // medium vertices in radians (negative: glossyAngle; integrators/medium_angle_pilot.h measures one).
    ManifoldPerturbation(const Scene &scene, double lambda, double glossyAngle, bool mediumChains = true,
                         double mediumAngle = -1);
    MutationType type() const override { return MutationType::Manifold; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;
    // Table 1 (ALGORITHMS.md §5.5): walks, converged walks, Newton iterations, chain sizes, reverse walks
    // and non-reversible proposals; the glossy and the medium vertices that proposals walked as specular; and the
    // converged walks whose chain crosses an index-matched boundary.
    void addCounters(ChainCounters &counters) const override;

    // A source: the vertex whose direction is perturbed and the direction of the walk (+1 towards the camera).
    struct Source {
        int vertex = 0, dir = 1;
    };
    // A strategy: the vertex whose direction is perturbed (x_a), the vertex that moves (x_b), the vertex that
    // stays (x_c).
    struct Strategy {
        int source = 0, moving = 0, fixed = 0;
    };
    // The sources of x, in a fixed order.
    std::vector<Source> sources(const PathView &x) const;
    // psi_spec: the probability that vertex v is part of a chain (1 ideal specular, 0 non-specular).
    double chainProbability(const PathVertex &v) const;
    // P(st | x) / P(source): the probability of st's classification of x's vertices.
    double classificationProbability(const PathView &x, const Strategy &st) const;
    // The direction kernel at x's vertex `source` towards `source + dir`.
    VonMisesFisher kernel(const Scene &scene, const PathView &x, int source, int dir) const;
    // The endpoint position kernel (§6.5): an isotropic 2D Gaussian offset in the tangent plane of a light or
    // aperture node, with variance rho / (2 pi lambda^2) per axis, rho the area of the light or aperture
    // (1 / its uniform position density), so that the peak density lambda^2 / rho is lambda^2 times the
    // uniform one, as the direction kernel's peak is lambda^2 p. Symmetric.
    struct GaussianOffset {
        double variance = 0;
        Vec2 sample(const Vec2 &u) const;
        double eval(const Vec2 &offset) const;
    };
    GaussianOffset positionKernel(const Scene &scene, const PathVertex &v) const;
    // rho of y's ideal specular chain between non-Dirac vertices `end` and `moving` (either order): the
    // manifold measure's density of a vertex traced through the chain over the canonical one (see above); 0
    // when the chain is degenerate.
    static double measureRatio(const PathView &y, int end, int moving);
    // R J of y for strategy st: T_M / T_canonical (see above); 0 when degenerate.
    double measureConversion(const PathView &y, const Strategy &st) const;
    // J of y for strategy st (manifold/offset_jacobian.h): 1 without glossy chain vertices, 0 when degenerate.
    static double offsetFactor(const PathView &y, const Strategy &st);

private:
    // 1 / rho of y's ideal sub-chains between `from` and x_b, times the free-flight probabilities of the
    // single edges between them. placedEnd: the second chain, whose walk places a medium x_b (its edge has no
    // free-flight probability); the first chain samples it by free flight.
    static double toCanonical(const PathView &y, int from, int moving, bool placedEnd = false);
    // The statistics of one chain's run (a MutationSet is built per chain, so nothing is shared).
    struct Statistics {
        double walks = 0, converged = 0, iterations = 0, chainVertices = 0, maxChainVertices = 0;
        double reverseWalks = 0, nonReversible = 0, glossySpecular = 0, mediumVertices = 0;
        double crossingWalks = 0;  // converged walks whose chain crosses an index-matched boundary
    };
    // Counts a glossy or medium vertex that a proposal walked as part of a chain (Table 1).
    void countChainVertex(const PathVertex &v) const;
    // Classifies the vertices after the source (one number per glossy vertex); nullopt on a failed walk.
    std::optional<Strategy> classify(Sampler &sampler, const PathView &x, const Source &source) const;
    // Traces direction d from y's x_a through x's first chain (Dirac lobes kept, glossy vertices scattered
    // about their offsets) to the new x_b.
    bool propagateChain(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y, const Strategy &st,
                        Vec3 d) const;
    // Reconnects y's new x_b to x_c through the second chain (x's chain vertices between them).
    bool connectChain(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                      const Strategy &st) const;

    double lambda_, glossyAngle_;
    bool mediumChains_;
    double mediumAngle_;
    ManifoldWalk walk_;
    mutable Statistics stats_;
};

}  // namespace pf
