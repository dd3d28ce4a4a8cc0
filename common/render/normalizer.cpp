#include "render/normalizer.h"

#include <algorithm>
#include <stdexcept>

namespace pf {

namespace {

// Stream ids that keep the resampling generators apart from every other generator seeded by the job seed.
constexpr uint64_t kResampleStream = 0x5e1ec7ULL;

}  // namespace

Normalizer::Normalizer(std::vector<SeedingResult> results) {
    for (SeedingResult &r : results) {
        pool_.insert(pool_.end(), r.candidates.begin(), r.candidates.end());
        if (depthLuminance_.size() < r.depthLuminance.size()) depthLuminance_.resize(r.depthLuminance.size(), 0.0);
        for (size_t d = 0; d < r.depthLuminance.size(); ++d) depthLuminance_[d] += r.depthLuminance[d];
        if (r.tuning.lambda > 0) tuning_.lambda = r.tuning.lambda;
        if (r.tuning.mediumAngle > 0) tuning_.mediumAngle = r.tuning.mediumAngle;
        if (!r.firstStage.enabled()) continue;
        if (!firstStage_.enabled())
            firstStage_ = r.firstStage;
        else
            for (size_t c = 0; c < r.firstStage.luminance.size(); ++c)
                firstStage_.luminance.at(c) += r.firstStage.luminance[c];
    }
    if (firstStage_.enabled()) reweightForSecondStage();
    cumulative_.reserve(pool_.size() + 1);
    cumulative_.push_back(0.0);
    for (const SeedCandidate &c : pool_) cumulative_.push_back(cumulative_.back() + c.weight);
    for (double l : depthLuminance_) luminance_ += l;
}

void Normalizer::reweightForSecondStage() {
    // The candidates of pi' = L / I are those of L with weights w / I (render/two_stage.h), and the
    // luminance per depth (b̂' and Kelemen's constants) is theirs.
    firstStage_ = firstStageImportance(std::move(firstStage_));
    std::fill(depthLuminance_.begin(), depthLuminance_.end(), 0.0);
    for (SeedCandidate &c : pool_) {
        c.weight /= firstStage_.luminance.at(c.cell);
        const size_t depth = static_cast<size_t>(c.record.s + c.record.t - 1);
        if (depthLuminance_.size() <= depth) depthLuminance_.resize(depth + 1, 0.0);
        depthLuminance_[depth] += c.weight;
    }
}

size_t Normalizer::find(double target) const {
    // The first candidate i with target < cumulative_[i + 1]; the last one when rounding puts target at
    // the total.
    const auto it = std::upper_bound(cumulative_.begin() + 1, cumulative_.end() - 1, target);
    return static_cast<size_t>(it - cumulative_.begin()) - 1;
}

std::vector<ChainSeed> Normalizer::resample(uint64_t seed, uint64_t taskIndex, uint64_t count) const {
    PCG32 rng(hashCombine(seed, taskIndex), kResampleStream);
    const double offset = rng.nextDouble(), total = cumulative_.back();
    std::vector<ChainSeed> seeds;
    if (!(total > 0)) return seeds;
    for (uint64_t k = 0; k < count; ++k) {
        const double target = (static_cast<double>(k) + offset) / static_cast<double>(count) * total;
        seeds.push_back({pool_[find(target)].record, 1.0});
    }
    return seeds;
}

double chainDepositScale(ChainKind kind, const ChainSeed &seed, uint64_t mutations) {
    return kind == ChainKind::Long ? 1.0 : seed.weight / static_cast<double>(mutations);
}

namespace {

// The figures of a chain result, added to a ChainImage's or another result's (the same fields).
template <class Sum>
void addFigures(Sum &sum, const ChainResult &result) {
    sum.mutations += result.mutations;
    sum.seedSamples += result.seedSamples;
    addCounts(sum.counts, result.counts);
    addCounters(sum.counters, result.counters);
    sum.rays += result.rays;
    sum.seconds += result.seconds;
}

}  // namespace

void mergeChainResult(ChainImage &image, const ChainResult &result, uint64_t tasks) {
    image.film.merge(result.film);
    image.tasks += tasks;
    addFigures(image, result);
}

void addChainResult(ChainResult &sum, const ChainResult &result) {
    SplatTiles *to = sum.film.tiles();
    const SplatTiles *from = result.film.tiles();
    // ImageBlock::merge adds into dense blocks only; a batch's sum stays as sparse as its tasks' films.
    if (!to || !from || to->tileCount() != from->tileCount() || sum.film.width() != result.film.width() ||
        sum.film.height() != result.film.height())
        throw std::invalid_argument("addChainResult: the films are not tiles of the same crop window");
    for (size_t t = 0; t < from->tileCount(); ++t) {
        const std::span<const double> values = from->tile(t);
        if (values.empty()) continue;
        const std::span<double> into = to->allocate(t);
        for (size_t k = 0; k < values.size(); ++k) into[k] += values[k];
    }
    sum.film.setInvalidSamples(sum.film.invalidSamples() + result.film.invalidSamples());
    addFigures(sum, result);
}

Bitmap developChains(const Film &film, const ChainImage &image, double scale) {
    return film.develop(image.film, scale);
}

}  // namespace pf
