// The Metropolis-Hastings core (mcmc/metropolis.h) on one-dimensional chains whose answers are known:
// the mixture toy of [TH Fig. 2.14] (ALGORITHMS.md §2.1), the Hastings ratio of an asymmetric proposal,
// and Kelemen's weights for independent large steps (§3.2). Every histogram comparison uses independent
// repeated runs: the run-to-run spread of a bin gives its standard error whatever the correlation
// between the steps of one chain.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "mcmc/metropolis.h"

namespace pf::test {
namespace {

constexpr int kBins = 20;
using Histogram = std::vector<double>;
using Density = std::function<double(double)>;

int binOf(double x) { return std::min(kBins - 1, static_cast<int>(x * kBins)); }

// The toy target of ALGORITHMS.md §2.1: two well separated normals restricted to [0, 1].
constexpr double kMixWeight[2] = {0.4, 0.6}, kMixMean[2] = {0.25, 0.75}, kMixSigma = 0.05;

double normalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

double mixture(double x) {
    if (x < 0 || x >= 1) return 0;
    double v = 0;
    for (int k = 0; k < 2; ++k)
        v += kMixWeight[k] * std::exp(-0.5 * std::pow((x - kMixMean[k]) / kMixSigma, 2)) /
             (kMixSigma * std::sqrt(2 * M_PI));
    return v;
}

double mixtureMass(double a, double b) {
    double m = 0;
    for (int k = 0; k < 2; ++k)
        m += kMixWeight[k] * (normalCdf((b - kMixMean[k]) / kMixSigma) - normalCdf((a - kMixMean[k]) / kMixSigma));
    return m;
}

// The target's mass per bin, normalized to a distribution.
Histogram mixtureBins() {
    Histogram h(kBins);
    for (int i = 0; i < kBins; ++i) h[static_cast<size_t>(i)] = mixtureMass(double(i) / kBins, double(i + 1) / kBins);
    const double total = mixtureMass(0, 1);
    for (double &v : h) v /= total;
    return h;
}

// [TH Fig. 2.14]'s proposals: MUTATE1 is an independent uniform proposal, MUTATE2 a uniform step in
// [x - 0.05, x + 0.05] (symmetric: proposals outside [0, 1] have zero target), MUTATE3 one of the two with
// probability 1/2. ClippedWindow draws the step within [0, 1], which makes it asymmetric near the ends.
enum class Mutation { Independent, Window, Mixture, ClippedWindow };
constexpr double kHalfWidth = 0.05;

class ToyChain final : public MarkovChain {
public:
    // `hastings` = false drops T from the proposals (the control of the Hastings-ratio test).
    ToyChain(Density target, Mutation mutation, double x0, Histogram &hist, bool hastings = true)
        : target_(std::move(target)), mutation_(mutation), hastings_(hastings), x_(x0), hist_(hist) {}

    double target() const override { return target_(x_); }
    Proposal propose(PCG32 &rng) override {
        Mutation m = mutation_;
        if (m == Mutation::Mixture) m = rng.nextDouble() < 0.5 ? Mutation::Independent : Mutation::Window;
        Proposal p;
        const double u = rng.nextDouble();
        if (m == Mutation::Independent) {
            y_ = u;
            p.independent = true;
        } else if (m == Mutation::Window) {
            y_ = x_ + (2 * u - 1) * kHalfWidth;
            p.type = 1;
        } else {
            y_ = lo(x_) + u * (hi(x_) - lo(x_));
            p.type = 1;
            if (hastings_) {
                p.forward = 1 / (hi(x_) - lo(x_));
                p.backward = 1 / (hi(y_) - lo(y_));
            }
        }
        p.target = target_(y_);
        return p;
    }
    void accept() override { x_ = y_; }
    void reject() override {}
    void splatCurrent(double w) override { hist_[static_cast<size_t>(binOf(x_))] += w; }
    void splatProposed(double w) override { hist_[static_cast<size_t>(binOf(y_))] += w; }

private:
    static double lo(double x) { return std::max(0.0, x - kHalfWidth); }
    static double hi(double x) { return std::min(1.0, x + kHalfWidth); }

    Density target_;
    Mutation mutation_;
    bool hastings_;
    double x_, y_ = 0;
    Histogram &hist_;
};

MutationCounts toyCounts() { return {{"independent", 0, 0}, {"window", 0, 0}}; }

// One run: `steps` transitions from x0, the deposits normalized to a distribution over the bins.
Histogram runToy(const Density &target, Mutation mutation, double x0, uint64_t steps, uint64_t seed,
                 bool hastings = true) {
    Histogram hist(kBins, 0.0);
    ToyChain chain(target, mutation, x0, hist, hastings);
    PCG32 rng(seed, 17);
    MutationCounts counts = toyCounts();
    runMetropolis(chain, steps, rng, nullptr, counts);
    for (double &v : hist) v /= static_cast<double>(steps);
    return hist;
}

struct BinStats {
    Histogram mean, stderr_;
};

BinStats over(const std::vector<Histogram> &runs) {
    BinStats s{Histogram(kBins, 0.0), Histogram(kBins, 0.0)};
    const double n = static_cast<double>(runs.size());
    for (size_t b = 0; b < kBins; ++b) {
        double sum = 0, sum2 = 0;
        for (const Histogram &h : runs) {
            sum += h[b];
            sum2 += h[b] * h[b];
        }
        s.mean[b] = sum / n;
        s.stderr_[b] = std::sqrt(std::max(0.0, sum2 / n - s.mean[b] * s.mean[b]) / (n - 1));
    }
    return s;
}

double totalVariation(const Histogram &a, const Histogram &b) {
    double d = 0;
    for (size_t i = 0; i < a.size(); ++i) d += std::abs(a[i] - b[i]);
    return 0.5 * d;
}

// Bins holding at least 0.5% of the target agree within 4 standard errors, the errors are small enough
// for that to mean something, and the total variation distance of the mean histogram is small.
void expectMatches(const BinStats &s, const Histogram &target, const char *what) {
    for (size_t b = 0; b < kBins; ++b) {
        if (target[b] < 0.005) continue;
        EXPECT_LT(s.stderr_[b], 0.1 * target[b]) << what << " bin " << b << ": too noisy to compare";
        EXPECT_NEAR(s.mean[b], target[b], 4 * s.stderr_[b]) << what << " bin " << b;
    }
    EXPECT_LT(totalVariation(s.mean, target), 0.02) << what;
}

constexpr int kRuns = 32;

TEST(MetropolisHastings, AcceptanceSatisfiesDetailedBalance) {
    PCG32 rng(3, 5);
    for (int i = 0; i < 1000; ++i) {
        const double pix = rng.nextDouble() * 10, piy = rng.nextDouble() * 10;
        const double txy = rng.nextDouble() * 3, tyx = rng.nextDouble() * 3;
        const double axy = acceptance(pix, {0, piy, txy, tyx, false});
        const double ayx = acceptance(piy, {0, pix, tyx, txy, false});
        EXPECT_NEAR(pix * txy * axy, piy * tyx * ayx, 1e-12 * (pix * txy + piy * tyx));
        EXPECT_TRUE(axy == 1 || ayx == 1);
    }
    // Zero or invalid targets and impossible reverse moves are rejected.
    EXPECT_EQ(acceptance(1.0, {0, 0.0, 1, 1, false}), 0.0);
    EXPECT_EQ(acceptance(1.0, {0, std::nan(""), 1, 1, false}), 0.0);
    EXPECT_EQ(acceptance(1.0, {0, INFINITY, 1, 1, false}), 0.0);
    EXPECT_EQ(acceptance(1.0, {0, 2.0, 1, 0, false}), 0.0);
}

// [TH Fig. 2.14]: after 10,000 steps from x = 0.5, MUTATE3 matches the target and MUTATE2 is stuck in the
// mode it first fell into. MUTATE1, a valid ergodic kernel, matches too.
TEST(MetropolisHastings, MixtureToyMutate3MatchesAndMutate2IsStuck) {
    const Histogram target = mixtureBins();
    for (Mutation m : {Mutation::Independent, Mutation::Window, Mutation::Mixture}) {
        std::vector<Histogram> runs;
        for (int r = 0; r < kRuns; ++r) runs.push_back(runToy(mixture, m, 0.5, 10000, 1000 + r));
        const char *name = m == Mutation::Independent ? "MUTATE1" : m == Mutation::Window ? "MUTATE2" : "MUTATE3";
        if (m == Mutation::Window) {
            // Every run stays in one mode: the other's mass (0.4 or 0.6 in the target) is missing.
            for (const Histogram &h : runs) {
                double left = 0;
                for (int b = 0; b < kBins / 2; ++b) left += h[static_cast<size_t>(b)];
                EXPECT_LT(std::min(left, 1 - left), 0.01) << name;
                EXPECT_GT(totalVariation(h, target), 0.35) << name;
            }
        } else {
            expectMatches(over(runs), target, name);
            for (const Histogram &h : runs) EXPECT_LT(totalVariation(h, target), 0.1) << name << ": a stuck run";
        }
    }
}

// A proposal that is asymmetric near the ends of [0, 1] samples a linear target correctly only with the
// Hastings ratio; without it the end bins are visibly wrong (the control shows the check can fail).
TEST(MetropolisHastings, HastingsRatioCorrectsAsymmetricProposals) {
    const Density linear = [](double x) { return x >= 0 && x < 1 ? 2 * x : 0.0; };
    Histogram target(kBins);
    for (int b = 0; b < kBins; ++b) target[static_cast<size_t>(b)] = (2.0 * b + 1) / (kBins * kBins);
    std::vector<Histogram> with, without;
    for (int r = 0; r < kRuns; ++r) {
        with.push_back(runToy(linear, Mutation::ClippedWindow, 0.5, 20000, 2000 + r));
        without.push_back(runToy(linear, Mutation::ClippedWindow, 0.5, 20000, 2000 + r, false));
    }
    expectMatches(over(with), target, "with the Hastings ratio");
    const BinStats control = over(without);
    const size_t last = kBins - 1;
    EXPECT_GT(std::abs(control.mean[last] - target[last]), 6 * control.stderr_[last])
        << "ignoring T should bias the end bins";
}

// Kelemen's weights combine the chain with its independent large steps. Started on a properly weighted
// state (one of N uniform samples drawn in proportion to the target, ALGORITHMS.md §2.4, with W = their
// mean target value as b̂), the deposits times W / M estimate the target's integral over each bin, with
// Kelemen's weights (c = W) as with Veach's expected values.
TEST(MetropolisHastings, KelemenWeightsEstimateTheIntegral) {
    Histogram exact(kBins);
    for (int b = 0; b < kBins; ++b)
        exact[static_cast<size_t>(b)] = mixtureMass(double(b) / kBins, double(b + 1) / kBins);
    constexpr uint64_t kSteps = 40000;
    constexpr int kPool = 4096;
    for (bool kelemen : {true, false}) {
        std::vector<Histogram> runs;
        for (int r = 0; r < 2 * kRuns; ++r) {
            PCG32 rng(3000 + r, 9);
            std::vector<double> pool(kPool), cdf(kPool + 1, 0.0);
            for (int i = 0; i < kPool; ++i) {
                pool[static_cast<size_t>(i)] = rng.nextDouble();
                cdf[static_cast<size_t>(i) + 1] = cdf[static_cast<size_t>(i)] + mixture(pool[static_cast<size_t>(i)]);
            }
            const double W = cdf.back() / kPool;
            const size_t j = static_cast<size_t>(
                std::upper_bound(cdf.begin() + 1, cdf.end(), rng.nextDouble() * cdf.back()) - cdf.begin() - 1);
            Histogram hist(kBins, 0.0);
            ToyChain chain(mixture, Mutation::Mixture, pool[j], hist);
            MutationCounts counts = toyCounts();
            const KelemenWeights weights{0.5, W};
            runMetropolis(chain, kSteps, rng, kelemen ? &weights : nullptr, counts);
            for (double &v : hist) v *= W / kSteps;
            runs.push_back(hist);
        }
        const BinStats s = over(runs);
        for (size_t b = 0; b < kBins; ++b) {
            if (exact[b] < 0.005) continue;
            // 1% of the bin's integral plus the average bin's.
            EXPECT_LT(s.stderr_[b], 0.01 * (exact[b] + 1.0 / kBins)) << "bin " << b << ": too noisy to compare";
            EXPECT_NEAR(s.mean[b], exact[b], 4 * s.stderr_[b]) << (kelemen ? "Kelemen" : "Veach") << " bin " << b;
        }
    }
}

// Counts: every step is one proposal of its type, accepted ones counted once.
TEST(MetropolisHastings, CountsProposalsPerType) {
    Histogram hist(kBins, 0.0);
    ToyChain chain(mixture, Mutation::Mixture, 0.5, hist);
    PCG32 rng(11, 1);
    MutationCounts counts = toyCounts();
    runMetropolis(chain, 4000, rng, nullptr, counts);
    EXPECT_EQ(counts[0].proposed + counts[1].proposed, 4000u);
    EXPECT_NEAR(static_cast<double>(counts[0].proposed), 2000.0, 4 * std::sqrt(1000.0));
    for (const MutationCount &c : counts) {
        EXPECT_GT(c.accepted, 0u) << c.name;
        EXPECT_LT(c.accepted, c.proposed) << c.name;
    }
    MutationCounts merged = {{"window", 1, 1}};
    addCounts(merged, counts);
    ASSERT_EQ(merged.size(), 2u);
    EXPECT_EQ(merged[0].proposed, counts[1].proposed + 1);
    EXPECT_EQ(merged[1].name, "independent");
}

}  // namespace
}  // namespace pf::test
