// Multiplexed MLT (`mmlt`; Hachisuka et al. 2014; ALGORITHMS.md §3.3): the BDPT strategy is a state
// dimension. A chain keeps the path depth d of its seed (per-depth chains; the seeding pool, whose weights
// are per strategy and so per depth, is the bootstrap); a coordinate picks one of the d + 2 strategies
// (s, d + 1 - s) uniformly, and Psi is that strategy's MIS-weighted contribution times d + 2, so chains
// spend their mutations on strategies in proportion to what they contribute. Kelemen's weights use the
// depth's own luminance b̂_d: large steps are independent samples of depth d only.
// Parameters: those of pssmlt (mcmc/pss_integrator.h) except `bidirectional`. --spp is mutations per pixel.
#pragma once
#include "mcmc/pss_integrator.h"

namespace pf {

class MMLT final : public PrimarySampleIntegrator {
public:
    explicit MMLT(const Properties &props) : PrimarySampleIntegrator(props) {}
    std::string name() const override { return "mmlt"; }
    // Chains keep their depth, so the image needs many of them: a task runs short chains.
    uint64_t chainsPerTask(const Scene &scene) const override;

protected:
    ChainSetup setup(const Scene &scene, const ChainTask &task, const ChainSeed &seed, const Vec2 &raster,
                     PCG32 &rng) const override;
};

}  // namespace pf
