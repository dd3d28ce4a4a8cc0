#include "mcmc/pss_chain.h"

#include <utility>

namespace pf {

double splatLuminance(const SplatList &splats, const FirstStageImage *firstStage) {
    double sum = 0;
    for (const Splat &s : splats) sum += s.value.luminance() * (firstStage ? firstStage->targetFactor(s.raster) : 1.0);
    return sum;
}

MutationCounts PrimarySampleChain::mutationTypes() { return {{"largeStep", 0, 0}, {"smallStep", 0, 0}}; }

PrimarySampleChain::PrimarySampleChain(PrimarySampleFunction psi, const PrimarySampleOptions &options, ImageBlock &film,
                                       double scale, const FirstStageImage *firstStage)
    : psi_(std::move(psi)), options_(options), film_(film), scale_(scale), firstStage_(firstStage), u_(options.sizes) {}

double PrimarySampleChain::start(const std::vector<double> &prefix, Sampler &source) {
    u_.start(prefix, source);
    current_.clear();
    psi_(u_, current_);
    currentTarget_ = splatLuminance(current_, firstStage_);
    return currentTarget_;
}

Proposal PrimarySampleChain::propose(PCG32 &rng) {
    const bool large = rng.nextDouble() < options_.largeStepProbability;
    u_.propose(large, rng);
    proposed_.clear();
    psi_(u_, proposed_);
    proposedTarget_ = splatLuminance(proposed_, firstStage_);
    Proposal p;
    p.type = large ? kLargeStep : kSmallStep;
    p.target = proposedTarget_;
    p.independent = large;
    return p;
}

void PrimarySampleChain::accept() {
    u_.accept();
    std::swap(current_, proposed_);
    currentTarget_ = proposedTarget_;
}

void PrimarySampleChain::reject() { u_.reject(); }

void PrimarySampleChain::deposit(const SplatList &splats, double target, double weight) {
    const double factor = weight * scale_ / target;
    for (const Splat &s : splats)
        if (!s.value.isBlack()) film_.splat(s.raster, s.value * factor);
}

void PrimarySampleChain::splatCurrent(double weight) { deposit(current_, currentTarget_, weight); }

void PrimarySampleChain::splatProposed(double weight) { deposit(proposed_, proposedTarget_, weight); }

}  // namespace pf
