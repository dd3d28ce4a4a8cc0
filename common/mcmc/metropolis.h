// The Metropolis-Hastings core shared by every Markov-chain integrator (PSSMLT, MMLT, Veach's MLT, ERPT):
// one transition is "propose y ~ T(x -> .), accept with a = min(1, pi(y) T(y -> x) / (pi(x) T(x -> y)))"
// (ALGORITHMS.md §2.1; Veach 1997 §11.2), and the image is recorded with expected values: both the current
// and the proposed state are deposited, weighted by 1 - a and a (Veach 1997 §11.3.5; ALGORITHMS.md §3.2),
// instead of only the state that survives. For proposals that are independent samples of the unit
// hypercube (Kelemen et al. 2002's large steps), the deposits can instead carry Kelemen's multiple
// importance sampling weights, which combine the chain with those independent samples.
//
// A chain is anything that implements MarkovChain: the core never sees its states, only the target
// values and transition densities of its proposals, and asks it to accept, reject and deposit.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "core/rng.h"

namespace pf {

// A proposed transition x -> y, as the chain reports it to the core.
struct Proposal {
    int type = 0;         // index of the mutation type in the chain's MutationCounts
    double target = 0;    // pi(y), unnormalized; zero (or not finite) means y is rejected
    double forward = 1;   // T(x -> y) and T(y -> x), up to any factor they share: only their ratio is used,
    double backward = 1;  // so symmetric proposals leave both at 1
    // y was drawn from the uniform density on the primary-sample hypercube, independently of x (Kelemen's
    // large step): with KelemenWeights it also counts as an independent sample of the image.
    bool independent = false;
};

// a(x -> y) for a chain in state x with pi(x) = currentTarget (ALGORITHMS.md §2.1). A proposal whose
// reverse move is impossible (backward = 0 while forward > 0) is never accepted: support must be
// symmetric, and this keeps a chain that violates it from drifting into states it cannot leave.
double acceptance(double currentTarget, const Proposal &proposal);

// Proposed and accepted transitions of one mutation type.
struct MutationCount {
    std::string name;
    uint64_t proposed = 0, accepted = 0;
};
using MutationCounts = std::vector<MutationCount>;
// Adds `from` into `into`, matching types by name (appending those `into` lacks).
void addCounts(MutationCounts &into, const MutationCounts &from);

// Further statistics of a chain, by name (the manifold walks of ALGORITHMS.md §5.5 Table 1: walks,
// walks converged, Newton iterations, manifold sizes, ...). Chains report sums, which merge by adding, or
// maxima, which merge by taking the larger; means are ratios of two sums taken when they are reported.
struct ChainCounter {
    enum class Merge { Sum, Max };
    std::string name;
    double value = 0;
    Merge merge = Merge::Sum;
};
using ChainCounters = std::vector<ChainCounter>;
// Merges `from` into `into`, matching counters by name (appending those `into` lacks).
void addCounters(ChainCounters &into, const ChainCounters &from);
// The counter `name` of `counters`, appended with value 0 if absent.
ChainCounter &counter(ChainCounters &counters, const std::string &name,
                      ChainCounter::Merge merge = ChainCounter::Merge::Sum);

class MarkovChain {
public:
    virtual ~MarkovChain() = default;
    // pi(x) of the current state (positive: chains start on states that carry energy).
    virtual double target() const = 0;
    // Draws y ~ T(x -> .) and evaluates it; y stays pending until accept() or reject().
    virtual Proposal propose(PCG32 &rng) = 0;
    virtual void accept() = 0;  // y becomes the current state
    virtual void reject() = 0;  // y is discarded, x stays
    // Deposit `weight` times the state's normalized contribution f / pi (ALGORITHMS.md §2.2).
    virtual void splatCurrent(double weight) = 0;
    virtual void splatProposed(double weight) = 0;
};

// Kelemen et al. 2002's weights (ALGORITHMS.md §3.2): with large steps taken with probability
// largeStepProbability and c the normalization constant of the chain's target (the integral of pi over
// the state space: for primary samples whose raster coordinates cover the film, b / pixel count, §2.3),
// the proposal y deposits (a + [large]) / (pi(y)/c + p_large) * f(y) and the current state x deposits
// (1 - a) / (pi(x)/c + p_large) * f(x). In units of f / pi, as MarkovChain deposits, and divided by c (the
// long-chain merge multiplies by b̂ = c times the pixel count, §2.5), these are
// (a + [large]) * pi / (pi + p_large * c) and (1 - a) * pi / (pi + p_large * c).
struct KelemenWeights {
    double largeStepProbability = 0;
    double normalization = 0;  // c
};

// Runs `steps` transitions of the chain, depositing with expected values (Veach's 1 - a and a when
// `kelemen` is null). The current state's deposits are accumulated and made once when it is left (and at
// the end), so a long rejection streak costs one deposit. `counts` is indexed by Proposal::type.
void runMetropolis(MarkovChain &chain, uint64_t steps, PCG32 &rng, const KelemenWeights *kelemen,
                   MutationCounts &counts);

}  // namespace pf
