#include "path/mis.h"

#include <cmath>

namespace pf {

namespace {

// The strategy set of one path: which strategies exist and the endpoint densities of direct sampling.
class Strategies {
public:
    Strategies(const Scene &scene, const PathView &path, const MISOptions &options)
        : path_(path), options_(options), n_(path.length()) {
        if (options.sampleDirect && n_ >= 3) {
            directEmitter_ = directDensity(scene, path.vertex(0), path.vertex(1));
            directSensor_ = directDensity(scene, path.vertex(n_ - 1), path.vertex(n_ - 2));
        }
    }

    int count() const { return n_ + 1; }
    bool directEmitter(int r) const { return options_.sampleDirect && r == 1 && n_ - r >= 2; }
    bool directSensor(int r) const { return options_.sampleDirect && r == n_ - 1 && r >= 2; }
    bool possible(int r) const {
        if (!options_.lightImage && r >= n_ - 1) return false;
        if (r == 0 || r == n_) return true;  // hitting an emitter or the lens: the density decides
        return (directEmitter(r) || path_.vertex(r - 1).isConnectable()) &&
               (directSensor(r) || path_.vertex(r).isConnectable());
    }
    // p_r divided by the plain product of p-> and p<- (which uses the walks' endpoint densities).
    double endpointFactor(int r, const std::vector<double> &pFwd, const std::vector<double> &pRev) const {
        double factor = 1.0;
        if (directEmitter(r)) factor *= directEmitter_ / pFwd.front();
        if (directSensor(r)) factor *= directSensor_ / pRev.back();
        return factor;
    }
    double direct(bool emitterSide) const { return emitterSide ? directEmitter_ : directSensor_; }

private:
    const PathView &path_;
    const MISOptions &options_;
    int n_;
    double directEmitter_ = 0, directSensor_ = 0;
};

// x^beta, with the two heuristics of MISOptions spelt out (pow is a measurable cost here).
double heuristicPower(double x, double beta) { return beta == 2.0 ? x * x : beta == 1.0 ? x : std::pow(x, beta); }

}  // namespace

double misWeight(const Scene &scene, const PathView &path, int s, const std::vector<double> &pFwd,
                 const std::vector<double> &pRev, const MISOptions &options) {
    const Strategies strategies(scene, path, options);
    const double self = strategies.endpointFactor(s, pFwd, pRev);
    const auto term = [&](int r, double ratio) {
        return strategies.possible(r)
                   ? heuristicPower(ratio * strategies.endpointFactor(r, pFwd, pRev) / self, options.exponent)
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

std::vector<double> strategyDensities(const Scene &scene, const PathView &path, const std::vector<double> &pFwd,
                                      const std::vector<double> &pRev, const MISOptions &options) {
    const Strategies strategies(scene, path, options);
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
