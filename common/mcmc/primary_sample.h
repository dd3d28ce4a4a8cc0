// The primary sample space of Kelemen et al. 2002 (ALGORITHMS.md §3.1-3.2): a Markov chain state is the
// vector of uniform numbers u_0, u_1, ... that a Monte Carlo sampler Psi consumes. PrimarySample is a
// Sampler, so that the integrators' own sampling code (BDPT) is Psi: it hands out u_i in order, and a
// proposal changes them lazily as Psi asks for them.
//
// Mutations (Kelemen et al. 2002 §4.1): a large step redraws every coordinate uniformly; a small step
// moves each one by a log-uniform offset of magnitude in [s1, s2] with a random sign, wrapped into
// [0, 1). Both are symmetric, so they leave T out of the acceptance ratio.
//
// Lazy evaluation: conceptually every transition mutates every coordinate, also those Psi did not read
// (the target does not depend on them, so they follow the mutation's random walk on the circle, which
// keeps them uniform). Each coordinate records the number of accepted transitions it reflects; when Psi
// reads it, it first catches up: redrawn if an accepted large step happened since, then the small steps
// of the accepted transitions it missed, one by one. Only then is the proposal's own change applied, after
// the value is backed up so that a rejection can restore it. Coordinates beyond the vector's end are
// created uniform. Fresh uniform numbers come from the chain's generator; while the chain's start is
// being evaluated they come from a `source` sampler instead, so that a chain can start from a path that
// an independent sampler produced (the seeding candidates, ALGORITHMS.md §2.4).
#pragma once
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "core/sampler.h"

namespace pf {

// Kelemen's small-step magnitudes (Mitsuba's mutationSizeLow / mutationSizeHigh).
struct MutationSizes {
    double low = 1.0 / 1024.0;  // s1
    double high = 1.0 / 64.0;   // s2
};

// Kelemen's small step: u +/- s2 * exp(-ln(s2 / s1) * xi), wrapped into [0, 1). ln(s2 / s1) is taken once
// (a chain steps every coordinate it reads, and the logarithm showed in profiles; issue 17).
class SmallStep {
public:
    explicit SmallStep(const MutationSizes &sizes) : high_(sizes.high), logRatio_(std::log(sizes.high / sizes.low)) {}
    double operator()(double u, PCG32 &rng) const;

private:
    double high_, logRatio_;
};

class PrimarySample final : public Sampler {
public:
    explicit PrimarySample(const MutationSizes &sizes) : smallStep_(sizes) {}

    // Starts a chain on the state `prefix` followed by the numbers `source` produces, for as many
    // coordinates as the next evaluation of Psi reads. The state is current once that evaluation is done
    // (no accept() needed).
    void start(const std::vector<double> &prefix, Sampler &source);
    // Prepares a proposal from the current state: the numbers handed out until accept() or reject() are
    // those of y.
    void propose(bool largeStep, PCG32 &rng);
    void accept();
    void reject();

    double next1D() override;

    // The coordinates the pending proposal has changed so far: index, value in x (after catching up) and
    // value in y. Detailed-balance tests compute T(x -> y) and T(y -> x) from these.
    struct Change {
        size_t index;
        double from, to;
    };
    std::vector<Change> changes() const;

private:
    struct Coordinate {
        double value = 0;
        uint64_t time = 0;  // accepted transitions this value reflects
    };
    double fresh();

    SmallStep smallStep_;
    std::vector<Coordinate> u_;
    std::vector<std::pair<size_t, Coordinate>> backup_;  // coordinates of x the proposal changed
    uint64_t accepted_ = 0;                              // transitions accepted so far: the current state's time
    uint64_t lastLarge_ = 0;                             // time of the last accepted large step
    size_t next_ = 0;                                    // index of the next coordinate Psi reads
    bool large_ = false;
    bool proposing_ = false;
    PCG32 *rng_ = nullptr;
    Sampler *source_ = nullptr;  // while starting
};

}  // namespace pf
