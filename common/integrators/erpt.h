// Energy redistribution path tracing (`erpt`; Cline et al. 2005; ALGORITHMS.md §5) seeded by BDPT, as in
// Jakob's variant ([TH 8]): every pixel's BDPT samples give seed paths with their weights, which launch
// short bursts of chainLength mutations using Veach's lens, caustic and multi-chain perturbations only,
// and no post-processing filter (Cline's filters are biased). Bursts need no ergodicity: the weighted seeds
// represent the image already, and each perturbation keeps that distribution (ALGORITHMS.md §5.2, §2.4).
//
// Energy per deposit (ALGORITHMS.md §5.3, Cline's bookkeeping): a seed of weight w launches
// nu = numChains * w / W chains on average (W the mean pixel luminance from the luminance pilot,
// render/pilot.h; nu at most maxChains when that is positive), floor(nu + U) with U uniform, each of weight
// w / nu. Every deposit then carries W / (numChains * chainLength) (more where the cap applies), on average
// numChains chains start per pixel and seed sample, and each seed's expected total stays w, for any W > 0
// that does not depend on the seeds. Seeds launch their own chains rather than drawing them from their
// pixel's samples: a pixel sample also holds light-tracing paths that land elsewhere, and a burst drawn
// from the pixel would carry the whole pixel's energy to wherever such a path lands. Tasks are (pass,
// block) pairs that sample their seeds themselves (render/burst.h), and the image is the mean of whole
// passes.
//
// Mitsuba 0.6 parameter names and defaults: maxDepth (-1), rrDepth (10), directSamples (16),
// numChains (1), maxChains (0: no cap on the chains of one seed), chainLength (100), lensPerturbation (true),
// causticPerturbation (true), multiChainPerturbation (true), bidirectionalMutation (false), lensSubpathMutation
// (false), manifoldPerturbation (false), portalPerturbation (false), lambda (50), manifoldGlossyAngle (1),
// luminanceSamples (15000: the pilot's BDPT samples); see integrators/mlt.h for those shared with mlt. Beyond
// Mitsuba: passMutations (2^20, or kManifoldPassMutations with the manifold perturbation), the expected
// mutations of one pass (render/burst.h), the step in which a time budget is spent.
// --spp is seed samples per pixel (rounds of render/burst.h; default: the scene's sampleCount).
//
// `mept` (manifold exploration path tracing, [TR §8]; ALGORITHMS.md §5.4) is this integrator with the
// manifold perturbation, which subsumes the lens, caustic and multi-chain perturbations, on by default in
// their place (path/manifold_perturbation.h); the same parameters switch any of them.
#pragma once
#include "integrators/mlt.h"

namespace pf {

// The default pass with the manifold perturbation on. Its mutations cost 1.7-3.2 times Veach's perturbations'
// (bench_manifold --bursts at 64²: 1.2·10^5 and 0.9·10^5 per core-second on volumetric-caustic-small and
// glass-egg, against erpt's 2.1·10^5 and 3.0·10^5), so a 2^20 pass is 8-11 core-seconds, and more on a loaded
// machine, where a timed render cannot stop before its first pass: volumetric-caustic-small at 1024², mept
// --time 60 on 2 threads sharing 2 cores with other work, rendered 117.9 s and 90.2 s (49.3 s on a lighter load).
// 2^18 rendered 60.3 s there. Smaller passes cost throughput at large films: a pass is split into about
// kBlocksPerPass tasks whatever its size, each with a film of the whole crop window (2^17: 52.0 s, but about a
// third fewer mutations per CPU second than 2^20 in the same runs).
constexpr int64_t kManifoldPassMutations = int64_t(1) << 18;

class ERPT final : public PathSpaceIntegrator {
public:
    // manifoldExploration: MEPT's default mutations and name.
    explicit ERPT(const Properties &props, bool manifoldExploration = false);
    std::string name() const override { return manifoldExploration_ ? "mept" : "erpt"; }
    ChainKind chainKind() const override { return ChainKind::Burst; }
    // The seeding BDPT of the pilot and of every burst task (one sample per covered pixel and pass).
    SeedingConfig seeding(const Scene &scene, int64_t spp = 0) const override;
    // The luminance pilot alone; with lambda = "auto" it also tunes λ on its paths (lambda_tuning.h), with
    // manifoldMediumAngle = "auto" it measures dtheta of medium vertices there (medium_angle_pilot.h).
    std::vector<SeedingTask> seedingTasks(const Scene &scene) const override;
    SeedingResult runSeeding(const Scene &scene, int64_t spp, uint64_t seed, const SeedingTask &task) const override;
    // `spp` rounds of the plan's passes (0: a time budget, unbounded).
    uint64_t chainTaskCount(const Scene &scene, int64_t spp) const override;
    // Task `index` is block index % blocks of pass index / blocks, with the pilot's W.
    ChainTask chainTask(const Scene &scene, const Normalizer &normalizer, uint64_t seed, int64_t spp,
                        uint64_t index) const override;
    // The task's seed candidates (render/burst.h), each launching floor(nu + U) bursts of weight m w / nu.
    std::vector<ChainSeed> taskSeeds(const Scene &scene, uint64_t seed, const ChainTask &task,
                                     uint64_t &seedSamples) const override;
    uint64_t tasksPerPass(const Scene &scene, int64_t spp) const override { return plan(scene, spp).blocks; }
    // The mean over whole passes: 1 / passes (blocks / tasks while a pass is under way, for previews).
    double chainImageScale(const Scene &scene, int64_t spp, const ChainImage &image, double luminance) const override;

    // The rounds a time budget's passes are planned for: numChains rounded down, at least 1 and at most the
    // scene's sampleCount, so that a seed sample launches at least one burst on average where numChains allows.
    // Not the sampleCount itself (as for a render of it), since a seed is a BDPT sample, which costs several
    // mutations: cornell-box as shipped (sampleCount 64, numChains 1) at 1024² spent 54% of an `erpt --time` render
    // in BDPT seeds for 1.6 mutations each, and made 20 mutations per pixel in 144 s, where 1 round made 100 in
    // 128 s. The same chains per pixel over the plan (numChains) as a render of sampleCount, and so the same pace
    // of the direct component.
    int64_t timeBudgetPlan(const Scene &scene) const override;
    // The passes of a render of `spp` rounds (0: a time budget, whose rounds are timeBudgetPlan's): Mitsuba's
    // numChains bursts per pixel over the whole render are numChains / rounds per round.
    BurstPlan plan(const Scene &scene, int64_t spp) const;
    // The expected number of chains nu of a seed of weight `candidateWeight` (one sample's) when the mean
    // pixel luminance is `meanLuminance` and a round launches `chainsPerPixel` bursts per pixel on average
    // (a pilot that saw no light, W = 0, gives every seed chainsPerPixel: still unbiased).
    double expectedChains(double candidateWeight, double meanLuminance, double chainsPerPixel) const;

private:
    double numChains_ = 1;
    int64_t maxChains_ = 0, chainLength_ = 100, luminanceSamples_ = 15000, passMutations_ = kDefaultPassMutations;
    bool manifoldExploration_ = false;
};

}  // namespace pf
