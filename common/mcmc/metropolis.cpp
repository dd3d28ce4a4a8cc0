#include "mcmc/metropolis.h"

#include <algorithm>
#include <cmath>

namespace pf {

double acceptance(double currentTarget, const Proposal &proposal) {
    if (!(proposal.target > 0) || !std::isfinite(proposal.target) || !(proposal.backward > 0)) return 0.0;
    const double ratio = proposal.target * proposal.backward / (currentTarget * proposal.forward);
    return std::isnan(ratio) ? 0.0 : std::min(1.0, ratio);
}

void addCounters(ChainCounters &into, const ChainCounters &from) {
    for (const ChainCounter &c : from) {
        ChainCounter &x = counter(into, c.name, c.merge);
        x.value = c.merge == ChainCounter::Merge::Max ? std::max(x.value, c.value) : x.value + c.value;
    }
}

ChainCounter &counter(ChainCounters &counters, const std::string &name, ChainCounter::Merge merge) {
    const auto it =
        std::find_if(counters.begin(), counters.end(), [&](const ChainCounter &x) { return x.name == name; });
    if (it != counters.end()) return *it;
    return counters.emplace_back(ChainCounter{name, 0.0, merge});
}

void addCounts(MutationCounts &into, const MutationCounts &from) {
    for (const MutationCount &c : from) {
        const auto it =
            std::find_if(into.begin(), into.end(), [&](const MutationCount &x) { return x.name == c.name; });
        if (it == into.end()) {
            into.push_back(c);
        } else {
            it->proposed += c.proposed;
            it->accepted += c.accepted;
        }
    }
}

void runMetropolis(MarkovChain &chain, uint64_t steps, PCG32 &rng, const KelemenWeights *kelemen,
                   MutationCounts &counts) {
    // Kelemen's factor pi / (pi + p_large * c); 1 for Veach's expected values.
    const auto misFactor = [&](double pi) {
        return kelemen ? pi / (pi + kelemen->largeStepProbability * kelemen->normalization) : 1.0;
    };
    double pending = 0;  // deposit weight the current state has gathered since it became current
    for (uint64_t i = 0; i < steps; ++i) {
        const double currentTarget = chain.target();
        const Proposal p = chain.propose(rng);
        const double a = acceptance(currentTarget, p);
        MutationCount &count = counts[static_cast<size_t>(p.type)];
        ++count.proposed;
        pending += (1 - a) * misFactor(currentTarget);
        // Not finite (a rejected NaN or infinite target) counts as zero: the test below fails for NaN.
        const double proposedWeight = (a + (kelemen && p.independent ? 1.0 : 0.0)) * misFactor(p.target);
        if (a >= 1 || (a > 0 && rng.nextDouble() < a)) {
            ++count.accepted;
            if (pending > 0) chain.splatCurrent(pending);
            chain.accept();
            pending = proposedWeight;
        } else {
            if (proposedWeight > 0) chain.splatProposed(proposedWeight);
            chain.reject();
        }
    }
    if (pending > 0) chain.splatCurrent(pending);
}

}  // namespace pf
