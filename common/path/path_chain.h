// The Markov chain of Veach's path-space MLT and of ERPT (Veach & Guibas 1997; Veach 1997 ch. 11; Cline et
// al. 2005): the state is a complete path x, the target pi(x) is the luminance of its contribution in the
// canonical measure (path/mutation.h; ALGORITHMS.md §2.2), and a transition selects one of the enabled
// mutations with probability proportional to applicability and draws a proposal from it. The core
// (mcmc/metropolis.h) accepts, and records with expected values; deposits are f / pi at the path's raster
// position (ALGORITHMS.md §2.2), a splat like every chain deposit (spread by the film's filter, not divided by its
// weights).
#pragma once
#include "image/film.h"
#include "mcmc/metropolis.h"
#include "path/mutation.h"
#include "render/two_stage.h"

namespace pf {

class PathChain final : public MarkovChain {
public:
    // pi is zero outside minVertices .. maxVertices vertices, index-matched crossings counted as vertices
    // as Mitsuba does (pathDepth() + 1; maxVertices < 0: unbounded): paths left to
    // a separately rendered component, or beyond maxDepth. Deposits go to `film`, times `scale`. With a first
    // stage (two-stage MLT, render/two_stage.h) pi is the luminance divided by its image where x lands.
    PathChain(const Scene &scene, const MutationSet &mutations, int minVertices, int maxVertices, ImageBlock &film,
              double scale, const FirstStageImage *firstStage = nullptr);
    // The counts of a chain whose MutationSet holds `types` in this order (Proposal::type), then "none":
    // steps at which no mutation applies to the current path (the chain stays).
    static MutationCounts mutationTypes(const std::vector<MutationType> &types);

    // Starts on x and returns pi(x).
    double start(const PathView &x);
    const MutablePath &current() const { return current_.path; }

    double target() const override { return current_.target; }
    Proposal propose(PCG32 &rng) override;
    void accept() override { std::swap(current_, proposed_); }
    void reject() override {}
    void splatCurrent(double weight) override { deposit(current_, weight); }
    void splatProposed(double weight) override { deposit(proposed_, weight); }

private:
    struct State {
        MutablePath path;
        ContributionTerms terms;  // f's factors
        Spectrum f;
        double target = 0;
        uint64_t applicable = 0;  // MutationSet::applicable(path) where target > 0
    };
    // Fills the terms, f, the target and the applicable mutations of state.path; with `record`, state.path is
    // the current path mutated by it and only the terms that the mutation changed are evaluated.
    void evaluate(State &state, const MutationRecord *record = nullptr) const;
    void deposit(const State &state, double weight);

    const Scene &scene_;
    const MutationSet &mutations_;
    int minVertices_, maxVertices_;
    ImageBlock &film_;
    double scale_;
    const FirstStageImage *firstStage_;
    State current_, proposed_;
};

}  // namespace pf
