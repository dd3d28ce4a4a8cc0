// Energy redistribution path tracing (`erpt`; Cline et al. 2005; ALGORITHMS.md §5) seeded by BDPT, as in
// Jakob's variant ([TH 8]): every pixel's BDPT samples give seed paths with their weights, which launch
// short bursts of chainLength mutations using Veach's lens, caustic and multi-chain perturbations only,
// and no post-processing filter (Cline's filters are biased). Bursts need no ergodicity: the weighted seeds
// represent the image already, and each perturbation keeps that distribution (ALGORITHMS.md §5.2, §2.4).
//
// Energy per deposit (ALGORITHMS.md §5.3, Cline's bookkeeping): a seed of weight w launches
// nu = numChains * w / W chains on average (W the mean pixel luminance, b̂ / pixels; nu at most maxChains
// when that is positive), floor(nu + U) with U uniform, each of weight w / nu. Every deposit then carries
// W / (numChains * chainLength) (more where the cap applies), on average numChains chains start per pixel,
// and each seed's expected total stays w. Seeds launch their own chains rather than drawing them from their
// pixel's pool: a pixel's pool also holds the light-tracing paths its samples splatted elsewhere, and a
// burst resampled from it would carry the whole pixel's energy to wherever such a path lands. The bursts'
// films are summed.
//
// Mitsuba 0.6 parameter names and defaults: maxDepth (-1), rrDepth (10), directSamples (16),
// numChains (1), maxChains (0: no cap on the chains of one seed), chainLength (100), lensPerturbation (true),
// causticPerturbation (true), multiChainPerturbation (true), bidirectionalMutation (false), lensSubpathMutation
// (false), manifoldPerturbation (false), lambda (50), manifoldGlossyAngle (1),
// luminanceSamples (15000; Mitsuba's pass for W, which here comes from the seeding, so it is only checked);
// see integrators/mlt.h for those shared with mlt. --spp is seed samples per pixel (default: the scene's
// sampleCount; see seeding()).
//
// `mept` (manifold exploration path tracing, [TR §8]; ALGORITHMS.md §5.4) is this integrator with the
// manifold perturbation, which subsumes the lens, caustic and multi-chain perturbations, on by default in
// their place (path/manifold_perturbation.h); the same parameters switch any of them.
#pragma once
#include "integrators/mlt.h"

namespace pf {

class ERPT final : public PathSpaceIntegrator {
public:
    // manifoldExploration: MEPT's default mutations and name.
    explicit ERPT(const Properties &props, bool manifoldExploration = false);
    std::string name() const override { return manifoldExploration_ ? "mept" : "erpt"; }
    ChainKind chainKind() const override { return ChainKind::Burst; }
    // The pool: `spp` BDPT samples per pixel (--spp), or the scene's sampleCount when spp is 0 (Mitsuba:
    // "the size of this pool is given by the samplesPerPixel parameter of the sample generator").
    SeedingConfig seeding(const Scene &scene, int64_t spp = 0) const override;
    // A task is a block of pixels, each with its bursts. The budget is the seeding's (seeding() above), and
    // under a time budget (spp = 0) the tasks after the last block are empty.
    uint64_t chainTaskCount(const Scene &scene, int64_t spp) const override;
    ChainTask chainTask(const Scene &scene, const Normalizer &normalizer, uint64_t seed, int64_t spp,
                        uint64_t index) const override;

    // The expected number of chains nu of a seed of weight `candidateWeight` when the mean pixel luminance
    // is `meanLuminance`.
    double expectedChains(double candidateWeight, double meanLuminance) const;

private:
    double numChains_ = 1;
    int64_t maxChains_ = 0, chainLength_ = 100;
    bool manifoldExploration_ = false;
};

}  // namespace pf
