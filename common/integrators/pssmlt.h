// Primary sample space MLT (`pssmlt`; Kelemen et al. 2002; ALGORITHMS.md §3.1-3.2) over bidirectional
// path tracing, as Mitsuba 0.6's pssmlt with bidirectional = true: Psi is one BDPT sample, a raster
// position drawn from the first two coordinates and then the two walks and every strategy; all of its
// MIS-weighted contributions are splatted where they land, and the target is their total luminance.
// Parameters: mcmc/pss_integrator.h, plus `bidirectional` (true; the unidirectional variant is not
// implemented). --spp is mutations per pixel (Mitsuba's sampleCount).
#pragma once
#include "mcmc/pss_integrator.h"

namespace pf {

class PSSMLT final : public PrimarySampleIntegrator {
public:
    explicit PSSMLT(const Properties &props);
    std::string name() const override { return "pssmlt"; }

protected:
    ChainSetup setup(const Scene &scene, const ChainTask &task, const ChainSeed &seed, const Vec2 &raster,
                     PCG32 &rng) const override;
};

}  // namespace pf
