// Multiple importance sampling over the BDPT strategies (ALGORITHMS.md §1.4; Veach 1997 §9.2, §10.2).
//
// A path x_0 .. x_{n-1} can come from n + 1 strategies r = 0 .. n (r vertices from the emitter walk).
// With p->(x_i) and p<-(x_i) the densities of ALGORITHMS.md §1.4, strategy r has density
//
//     p_r = prod_{i<r} p->(x_i) * prod_{i>=r} p<-(x_i),
//
// except that with direct sampling (sampleDirect) the strategy r = 1 draws x_0 from x_1 and r = n - 1
// draws x_{n-1} from x_{n-2} (next-event estimation and light tracing towards the sensor), so their
// endpoint densities are those of direct sampling (path/vertex.h: directDensity). A strategy is
// possible when its connection does not touch a Dirac vertex (a direct endpoint may be one: that is how
// parallel light is connected); strategies whose density is zero drop out by themselves. The weight of
// strategy s is p_s^beta / sum_r p_r^beta (beta = 2: power heuristic, 1: balance heuristic).
#pragma once
#include <vector>

#include "path/path.h"

namespace pf {

struct MISOptions {
    double exponent = 2.0;     // beta
    bool sampleDirect = true;  // r = 1 and r = n - 1 sample their endpoint directly (when n >= 3)
    bool lightImage = true;    // the strategies that land on other pixels (t = n - r <= 1) take part
};

// The weight of strategy s for a path with densities d (as BDPT keeps them, JoinedPath::densities),
// computed with running ratios p_r / p_s outwards from s.
double misWeight(const PathDensities &d, int s, const MISOptions &options);
// The same from p-> and p<- alone (e.g. as EVALPDF gives them, evalDensities): the rest of
// PathDensities is taken from the path's vertices.
double misWeight(const Scene &scene, const PathView &path, int s, const std::vector<double> &pFwd,
                 const std::vector<double> &pRev, const MISOptions &options);

// Every strategy's density p_r (r = 0 .. n) as the explicit product above, zero for impossible
// strategies: the independent check of misWeight, and what strategy-aware Markov chains need.
std::vector<double> strategyDensities(const Scene &scene, const PathView &path, const std::vector<double> &pFwd,
                                      const std::vector<double> &pRev, const MISOptions &options);

}  // namespace pf
