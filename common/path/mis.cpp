#include "path/mis.h"

#include <cmath>

namespace pf {

namespace {

// The strategy set of one path: which strategies exist and the endpoint densities of direct sampling.
class Strategies {
public:
    Strategies(const PathDensities &d, const MISOptions &options)
        : d_(d), options_(options), n_(static_cast<int>(d.pFwd.size())) {}

    int count() const { return n_ + 1; }
    bool directEmitter(int r) const { return options_.sampleDirect && r == 1 && n_ - r >= 2; }
    bool directSensor(int r) const { return options_.sampleDirect && r == n_ - 1 && r >= 2; }
    bool possible(int r) const {
        if (!options_.lightImage && r >= n_ - 1) return false;
        if (r == 0 || r == n_) return true;  // hitting an emitter or the lens: the density decides
        return (directEmitter(r) || d_.connectable[static_cast<size_t>(r - 1)]) &&
               (directSensor(r) || d_.connectable[static_cast<size_t>(r)]);
    }
    // p_r divided by the plain product of p-> and p<- (which uses the walks' endpoint densities).
    double endpointFactor(int r) const {
        double factor = 1.0;
        if (directEmitter(r)) factor *= d_.directEmitter / d_.pFwd.front();
        if (directSensor(r)) factor *= d_.directSensor / d_.pRev.back();
        return factor;
    }
    double direct(bool emitterSide) const { return emitterSide ? d_.directEmitter : d_.directSensor; }

private:
    const PathDensities &d_;
    const MISOptions &options_;
    int n_;
};

// x^beta, with the two heuristics of MISOptions spelt out (pow is a measurable cost here).
double heuristicPower(double x, double beta) { return beta == 2.0 ? x * x : beta == 1.0 ? x : std::pow(x, beta); }

// PathDensities of any path from its p-> and p<-: connectability from its vertices, direct densities
// with directDensity.
PathDensities gather(const Scene &scene, const PathView &path, const std::vector<double> &pFwd,
                     const std::vector<double> &pRev, const MISOptions &options) {
    PathDensities d;
    d.pFwd = pFwd;
    d.pRev = pRev;
    const int n = path.length();
    for (int i = 0; i < n; ++i) d.connectable.push_back(path.vertex(i).isConnectable());
    if (options.sampleDirect && n >= 3) {
        d.directEmitter = directDensity(scene, path.vertex(0), path.vertex(1));
        d.directSensor = directDensity(scene, path.vertex(n - 1), path.vertex(n - 2));
    }
    return d;
}

}  // namespace

double misWeight(const PathDensities &d, int s, const MISOptions &options) {
    const Strategies strategies(d, options);
    const std::vector<double> &pFwd = d.pFwd, &pRev = d.pRev;
    const double self = strategies.endpointFactor(s);
    const auto term = [&](int r, double ratio) {
        return strategies.possible(r) ? heuristicPower(ratio * strategies.endpointFactor(r) / self, options.exponent)
                                      : 0.0;
    };
    double sum = 1.0;
    // p_r / p_{r+1} = p<-(x_r) / p->(x_r): moving the junction towards the emitter.
    double ratio = 1.0;
    for (int r = s - 1; r >= 0 && pFwd[static_cast<size_t>(r)] > 0; --r) {
        ratio *= pRev[static_cast<size_t>(r)] / pFwd[static_cast<size_t>(r)];
        sum += term(r, ratio);
    }
    // p_{r+1} / p_r = p->(x_r) / p<-(x_r): moving it towards the sensor.
    ratio = 1.0;
    for (int r = s + 1; r < strategies.count() && pRev[static_cast<size_t>(r - 1)] > 0; ++r) {
        ratio *= pFwd[static_cast<size_t>(r - 1)] / pRev[static_cast<size_t>(r - 1)];
        sum += term(r, ratio);
    }
    return 1.0 / sum;
}

double misWeight(const Scene &scene, const PathView &path, int s, const std::vector<double> &pFwd,
                 const std::vector<double> &pRev, const MISOptions &options) {
    return misWeight(gather(scene, path, pFwd, pRev, options), s, options);
}

std::vector<double> strategyDensities(const Scene &scene, const PathView &path, const std::vector<double> &pFwd,
                                      const std::vector<double> &pRev, const MISOptions &options) {
    const PathDensities d = gather(scene, path, pFwd, pRev, options);
    const Strategies strategies(d, options);
    const int n = path.length();
    std::vector<double> p(static_cast<size_t>(strategies.count()), 0.0);
    for (int r = 0; r <= n; ++r) {
        if (!strategies.possible(r)) continue;
        double product = 1.0;
        for (int i = 0; i < n; ++i) {
            const size_t k = static_cast<size_t>(i);
            if (i < r)
                product *= i == 0 && strategies.directEmitter(r) ? strategies.direct(true) : pFwd[k];
            else
                product *= i == n - 1 && strategies.directSensor(r) ? strategies.direct(false) : pRev[k];
        }
        p[static_cast<size_t>(r)] = product;
    }
    return p;
}

}  // namespace pf
