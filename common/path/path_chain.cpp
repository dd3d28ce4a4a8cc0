#include "path/path_chain.h"

#include <cmath>

namespace pf {

namespace {

// The chain's generator as the Sampler that mutations draw from.
class ChainSampler final : public Sampler {
public:
    explicit ChainSampler(PCG32 &rng) : rng_(rng) {}
    double next1D() override { return rng_.nextDouble(); }

private:
    PCG32 &rng_;
};

}  // namespace

PathChain::PathChain(const Scene &scene, const MutationSet &mutations, int minVertices, int maxVertices,
                     ImageBlock &film, double scale, const FirstStageImage *firstStage)
    : scene_(scene),
      mutations_(mutations),
      minVertices_(minVertices),
      maxVertices_(maxVertices),
      film_(film),
      scale_(scale),
      firstStage_(firstStage) {}

MutationCounts PathChain::mutationTypes(const std::vector<MutationType> &types) {
    MutationCounts counts;
    for (const MutationType type : types) counts.push_back({mutationName(type), 0, 0});
    counts.push_back({"none", 0, 0});
    return counts;
}

void PathChain::evaluate(State &state, const MutationRecord *record) const {
    // Vertices as Mitsuba counts them: the index-matched crossings are vertices of its paths (path.h).
    const int n = pathDepth(state.path) + 1;
    const bool inRange = n >= minVertices_ && (maxVertices_ < 0 || n <= maxVertices_);
    state.f = Spectrum(0.0);
    if (inRange) {
        // The canonical measure (mutation.h: chainContribution).
        if (record)
            state.terms.update(scene_, state.path, TransportMode::Radiance, current_.terms, record->l, record->m,
                               record->added);
        else
            state.terms.evaluate(scene_, state.path, TransportMode::Radiance);
        state.f = state.terms.product();
    }
    state.target = state.f.luminance() * (firstStage_ ? firstStage_->targetFactor(state.path.raster()) : 1.0);
    state.applicable = state.target > 0 ? mutations_.applicable(state.path) : 0;
}

double PathChain::start(const PathView &x) {
    current_.path = MutablePath(x);
    evaluate(current_);
    return current_.target;
}

Proposal PathChain::propose(PCG32 &rng) {
    ChainSampler sampler(rng);
    const MutablePath &x = current_.path;
    const int k = mutations_.select(current_.applicable, sampler.next1D());
    Proposal p;
    p.target = 0;
    p.type = k < 0 ? static_cast<int>(mutations_.size()) : k;
    if (k < 0) return p;
    const Mutation &mutation = mutations_[static_cast<size_t>(k)];
    MutationRecord record;
    if (!mutation.sample(scene_, sampler, x, proposed_.path, record)) return p;
    evaluate(proposed_, &record);
    if (!(proposed_.target > 0) || !std::isfinite(proposed_.target)) return p;
    const MutablePath &y = proposed_.path;
    p.forward = mutations_.selectionProbability(current_.applicable, static_cast<size_t>(k)) *
                mutation.density(scene_, x, y, record);
    p.backward = mutations_.selectionProbability(proposed_.applicable, static_cast<size_t>(k)) *
                 mutation.density(scene_, y, x, record.reverse());
    // A proposal the mutation cannot have made (T(x -> y) = 0, from round-off at the edge of its support) or
    // with a non-finite density carries no information: it is rejected.
    if (p.forward > 0 && std::isfinite(p.forward) && std::isfinite(p.backward)) p.target = proposed_.target;
    return p;
}

void PathChain::deposit(const State &state, double weight) {
    film_.splat(state.path.raster(), state.f * (weight * scale_ / state.target));
}

}  // namespace pf
