// What PSSMLT and MMLT share (Kelemen et al. 2002; Hachisuka et al. 2014; ALGORITHMS.md §3): Mitsuba 0.6's
// `pssmlt` parameters, the BDPT both run over and seed from, the separately rendered direct component,
// and the chain itself: a PrimarySampleChain started on a seeding candidate and run by the MH core. The two
// integrators differ only in Psi (all of a BDPT sample's strategies, or one chosen by a coordinate) and in
// the normalization constant of Kelemen's weights.
//
// Parameters (Mitsuba 0.6 names and defaults):
//   maxDepth (-1), rrDepth (5)      path depth bounds of the underlying BDPT
//   directSamples (16)              samples per pixel of the direct component (paths of at most two edges),
//                                   rendered by volpath without chains; 0 hides it, -1 leaves it to the chains
//   luminanceSamples (100000)       BDPT samples for seeding and b̂, rounded up to whole samples per pixel
//   pLarge (0.3)                    probability of a large step
//   kelemenStyleWeights (true)      Kelemen's MIS weights for large steps, else Veach's expected values.
//                                   Kelemen's weights need the target's integral, which is b̂ from the
//                                   pool that also seeds the chains: the weights then depend on that pool,
//                                   which leaves a bias of the order of b̂'s relative variance (as in
//                                   Mitsuba); with Veach's expected values the image is exactly unbiased
//                                   (ALGORITHMS.md §2.4).
//   directSampling (true)           BDPT's s = 1 / t = 1 strategies sample their endpoint directly
//   mutationSizeLow (1/1024), mutationSizeHigh (1/64)   small-step magnitudes s1, s2
//   twoStage (false)                two-stage MLT (render/two_stage.h): a first stage's low-resolution image
//                                   I steers the chains, whose target becomes L / I
//   firstStageSizeReduction (16)    the first stage's image is this many times smaller in x and y
#pragma once
#include <memory>
#include <optional>

#include "integrators/bdpt.h"
#include "mcmc/pss_chain.h"
#include "render/chain.h"

namespace pf {

class PrimarySampleIntegrator : public ChainIntegrator {
public:
    SeedingConfig seeding(const Scene &scene, int64_t spp = 0) const override;
    MutationCounts mutationTypes() const override { return PrimarySampleChain::mutationTypes(); }
    void runChain(const Scene &scene, uint64_t jobSeed, const ChainTask &task, const ChainSeed &seed, double scale,
                  PCG32 &rng, ImageBlock &film, MutationCounts &counts, ChainCounters &counters) const override;
    const SamplingIntegrator *directIntegrator() const override { return direct_.get(); }
    int64_t directSamples() const override { return directSamples_; }

    // A chain on the start state that `seed` names, ready to run (runChain runs it; tests step it).
    struct StartedChain {
        std::unique_ptr<PrimarySampleChain> chain;
        std::optional<KelemenWeights> kelemen;
    };
    StartedChain startChain(const Scene &scene, uint64_t jobSeed, const ChainTask &task, const ChainSeed &seed,
                            double scale, PCG32 &rng, ImageBlock &film) const;

    const BDPT &bdpt() const { return *bdpt_; }
    // Paths with fewer edges are left to the direct component.
    int minDepth() const { return directSamples_ >= 0 ? 3 : 1; }

protected:
    explicit PrimarySampleIntegrator(const Properties &props);

    // The algorithm's Psi for a chain from `seed`, the coordinates of its start state that precede the BDPT
    // numbers (`raster`: where the seed sample lies on the film), and the image luminance (sum over pixels)
    // of the chain's target, from which Kelemen's c follows.
    struct ChainSetup {
        PrimarySampleFunction psi;
        std::vector<double> prefix;
        double normalization = 0;
    };
    virtual ChainSetup setup(const Scene &scene, const ChainTask &task, const ChainSeed &seed, const Vec2 &raster,
                             PCG32 &rng) const = 0;

private:
    std::unique_ptr<BDPT> bdpt_;
    std::unique_ptr<SamplingIntegrator> direct_;  // integrators/path.h: makeDirectComponent
    int64_t directSamples_ = 16, luminanceSamples_ = 100000;
    bool kelemenWeights_ = true;
    int firstStageReduction_ = 0;
    PrimarySampleOptions options_;
};

}  // namespace pf
