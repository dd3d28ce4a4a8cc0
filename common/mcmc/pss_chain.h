// A Markov chain on the primary sample space (Kelemen et al. 2002; ALGORITHMS.md §3.2): the state is a
// PrimarySample vector u, Psi maps it to the splats (raster position, value) of one Monte Carlo sample,
// and the target is pi(u) = the total luminance of those splats. A transition is a large step with
// probability p_large, otherwise a small step; both are symmetric. PSSMLT and MMLT differ only in Psi.
#pragma once
#include <functional>

#include "image/film.h"
#include "integrators/integrator.h"
#include "mcmc/metropolis.h"
#include "mcmc/primary_sample.h"
#include "render/two_stage.h"

namespace pf {

// Psi: evaluates the sample that `sampler` (a PrimarySample) describes, appending its contributions.
using PrimarySampleFunction = std::function<void(Sampler &sampler, SplatList &splats)>;

struct PrimarySampleOptions {
    double largeStepProbability = 0.3;  // Mitsuba's pLarge
    MutationSizes sizes;
};

// The luminance of a list of splats: pi of the state that produced them; with a first stage (two-stage
// MLT, render/two_stage.h) each splat's luminance divided by the first stage's image where it lands.
double splatLuminance(const SplatList &splats, const FirstStageImage *firstStage = nullptr);

class PrimarySampleChain final : public MarkovChain {
public:
    static constexpr int kLargeStep = 0, kSmallStep = 1;
    // The mutation types in Proposal::type order, with zero counts.
    static MutationCounts mutationTypes();

    // Deposits go to `film`, multiplied by `scale`; the target is splatLuminance(splats, firstStage).
    PrimarySampleChain(PrimarySampleFunction psi, const PrimarySampleOptions &options, ImageBlock &film, double scale,
                       const FirstStageImage *firstStage = nullptr);
    // Evaluates the start state (see PrimarySample::start) and returns its pi.
    double start(const std::vector<double> &prefix, Sampler &source);

    double target() const override { return currentTarget_; }
    Proposal propose(PCG32 &rng) override;
    void accept() override;
    void reject() override;
    void splatCurrent(double weight) override;
    void splatProposed(double weight) override;

    const PrimarySample &primarySample() const { return u_; }

private:
    void deposit(const SplatList &splats, double target, double weight);

    PrimarySampleFunction psi_;
    PrimarySampleOptions options_;
    ImageBlock &film_;
    double scale_;
    const FirstStageImage *firstStage_;
    PrimarySample u_;
    SplatList current_, proposed_;
    double currentTarget_ = 0, proposedTarget_ = 0;
};

}  // namespace pf
