#include "path/bidirectional_mutation.h"

#include <bit>
#include <climits>
#include <cstdint>

namespace pf {

namespace {

// 2^e, the value std::ldexp(1.0, e) gives, built from its bits where it is a normal number: the mutation takes
// dozens per step, and the library call showed in profiles (issue 17).
double powerOfTwo(int e) {
    if (e < -1022 || e > 1023) return std::ldexp(1.0, e);
    return std::bit_cast<double>(static_cast<uint64_t>(e + 1023) << 52);
}

// sum_{j = j0}^{j1} 2^-j.
double halfPowers(int64_t j0, int64_t j1) {
    return j1 < j0 ? 0.0
                   : powerOfTwo(static_cast<int>(std::min<int64_t>(1 - j0, 1100))) -
                         powerOfTwo(static_cast<int>(std::max<int64_t>(-j1, -1100)));
}

// The two-tailed geometric distribution with ratio 1/2 around `centre`, restricted to [lo, hi].
class TwoTailedGeometric {
public:
    TwoTailedGeometric(int centre, int lo, int hi) : c_(centre), lo_(lo), hi_(hi) {
        const int64_t c = centre;
        if (lo <= std::min(centre, hi)) norm_ += halfPowers(std::max<int64_t>(0, c - hi), c - lo);
        if (hi > centre) norm_ += halfPowers(std::max<int64_t>(1, int64_t(lo) - c), int64_t(hi) - c);
    }
    double pmf(int k) const { return k < lo_ || k > hi_ || !(norm_ > 0) ? 0.0 : weight(k) / norm_; }
    int sample(double u) const {
        const double target = u * norm_;
        double sum = 0;
        for (int k = lo_;; ++k) {
            const double w = weight(k);
            sum += w;
            if (sum > target || k == hi_ || w == 0) return k;
        }
    }

private:
    double weight(int k) const { return powerOfTwo(-std::min(std::abs(k - c_), 1100)); }
    int c_, lo_, hi_;
    double norm_ = 0;
};

// A kept end of the deleted range: non-specular and not a point (see the header).
bool keepable(const PathVertex &v) { return isNonSpecular(v) && !v.hasDeltaPosition(); }

// The emitter-walk steps s that may regenerate `added` vertices between x_l and x_m of an n-vertex path:
// every split, except that the sensor node must come from the sensor walk (no mutation reaches the lens
// from the light side).
struct SplitRange {
    int first = 0, last = -1;
    int count() const { return last - first + 1; }
};
SplitRange splitRange(int n, int m, int added) { return {0, m == n ? added - 1 : added}; }

}  // namespace

BidirectionalMutation::BidirectionalMutation(int minVertices, int maxVertices)
    : minVertices_(minVertices), maxVertices_(maxVertices < 0 ? INT_MAX : maxVertices) {}

void BidirectionalMutation::deletionPositions(const PathView &x, int kd, int ka, std::vector<int> &positions) const {
    const int n = x.length();
    int lo = -1, hi = n - kd;
    if (kd == 1 || ka == 1) ++lo, --hi;
    positions.clear();
    for (int l = lo; l <= hi; ++l)
        if ((l < 0 || keepable(x.vertex(l))) && (l + kd >= n || keepable(x.vertex(l + kd)))) positions.push_back(l);
}

double BidirectionalMutation::choiceProbability(const PathView &x, int l, int kd, int added) const {
    const int n = x.length(), length = n - kd + 1 + added;
    const double pLength = TwoTailedGeometric(n, minVertices_, maxVertices_).pmf(length);
    const int minDeletion = std::max(length == n ? 2 : 1, n - length + 1);
    const double pDeletion = TwoTailedGeometric(2, minDeletion, n + 1).pmf(kd);
    thread_local std::vector<int> positions;
    deletionPositions(x, kd, added + 1, positions);
    const bool found = std::find(positions.begin(), positions.end(), l) != positions.end();
    return found ? pLength * pDeletion / static_cast<double>(positions.size()) : 0.0;
}

bool BidirectionalMutation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                   MutationRecord &record) const {
    const int n = x.length();
    const int length = TwoTailedGeometric(n, minVertices_, maxVertices_).sample(sampler.next1D());
    const int minDeletion = std::max(length == n ? 2 : 1, n - length + 1);
    const int kd = TwoTailedGeometric(2, minDeletion, n + 1).sample(sampler.next1D());
    const int ka = length - n + kd;
    thread_local std::vector<int> positions;
    deletionPositions(x, kd, ka, positions);
    const double uPosition = sampler.next1D(), uSplit = sampler.next1D();
    if (positions.empty()) return false;
    const int l = positions[std::min(positions.size() - 1, static_cast<size_t>(uPosition * positions.size()))];
    const int m = l + kd, added = ka - 1;
    const SplitRange split = splitRange(n, m, added);
    if (split.count() <= 0) return false;
    const int s = split.first + std::min(split.count() - 1, static_cast<int>(uSplit * split.count()));
    record = {l, m, added};
    y.splice(x, l, m, added);
    return extendWalk(scene, sampler, TransportMode::Importance, y, l, s) &&
           extendWalk(scene, sampler, TransportMode::Radiance, y, l + added + 1, added - s) &&
           connectJunction(scene, y, l + s);
}

double BidirectionalMutation::density(const Scene &scene, const PathView &x, const PathView &y,
                                      const MutationRecord &record) const {
    const int n = x.length(), l = record.l, m = record.m, added = record.added, kd = m - l;
    if (y.length() != n - kd + 1 + added) return 0.0;
    const double choice = choiceProbability(x, l, kd, added);
    const SplitRange split = splitRange(n, m, added);
    if (!(choice > 0) || split.count() <= 0) return 0.0;
    // Only the regenerated vertices' densities enter (walkDensity); buffers kept per thread, as a chain calls
    // this twice per step.
    thread_local std::vector<double> pFwd, pRev;
    evalDensities(scene, y, l + 1, l + added, pFwd, pRev);
    double sum = 0;
    for (int s = split.first; s <= split.last; ++s)
        if (isJunction(y, l + s)) sum += walkDensity(scene, y, l, s, l + added + 1, pFwd, pRev);
    return choice * sum / split.count();
}

}  // namespace pf
