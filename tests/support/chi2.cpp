#include "support/chi2.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace pf::test {

namespace {

// Series representation of the lower regularized gamma P(a, x), valid for x < a + 1.
double gammaPSeries(double a, double x) {
    double sum = 1.0 / a, term = sum, ap = a;
    for (int n = 0; n < 10000; ++n) {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if (std::abs(term) < std::abs(sum) * 1e-15) break;
    }
    return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Continued fraction (modified Lentz) for Q(a, x), valid for x >= a + 1.
double gammaQContinuedFraction(double a, double x) {
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 10000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < tiny) d = tiny;
        c = b + an / c;
        if (std::abs(c) < tiny) c = tiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < 1e-15) break;
    }
    return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double gammaQ(double a, double x) {
    if (x <= 0) return 1.0;
    if (x < a + 1.0) return 1.0 - gammaPSeries(a, x);
    return gammaQContinuedFraction(a, x);
}

Chi2Result chi2Histogram(const std::vector<double> &observed, const std::vector<double> &expected,
                         double significance, int testCount) {
    Chi2Result r;
    // Sort cells by expected count and pool the small ones (expected < 5) into a single cell.
    std::vector<size_t> order(expected.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });
    double pooledObs = 0, pooledExp = 0, stat = 0;
    int cells = 0;
    std::ostringstream worst;
    double worstTerm = 0;
    for (size_t k : order) {
        // Cells the pdf gives (numerically) no mass are pooled with the other small cells: samples there
        // still count against the pool's tiny expectation, so a sampler that leaves the pdf's support
        // fails, while a support edge that the quadrature grid just misses does not.
        if (expected[k] < 5) {
            pooledObs += observed[k];
            pooledExp += expected[k];
            continue;
        }
        const double diff = observed[k] - expected[k];
        const double term = diff * diff / expected[k];
        if (term > worstTerm) {
            worstTerm = term;
            worst.str("");
            worst << "cell " << k << ": observed " << observed[k] << ", expected " << expected[k];
        }
        stat += term;
        ++cells;
    }
    if (pooledExp > 0) {
        const double diff = pooledObs - pooledExp;
        stat += diff * diff / pooledExp;
        ++cells;
    }
    r.statistic = stat;
    r.dof = std::max(1, cells - 1);
    r.pValue = gammaQ(r.dof / 2.0, stat / 2.0);
    const double threshold = 1.0 - std::pow(1.0 - significance, 1.0 / std::max(1, testCount));
    r.passed = r.pValue >= threshold;
    std::ostringstream os;
    os << "chi2 = " << stat << ", dof = " << r.dof << ", p = " << r.pValue << " (threshold " << threshold
       << "); largest deviation at " << worst.str();
    r.report = os.str();
    return r;
}

Chi2Result chi2Sphere(const DirectionSampler &sample, const DirectionPdf &pdf, const Chi2Options &opt) {
    const int nT = opt.thetaBins, nP = opt.phiBins;
    std::vector<double> observed(static_cast<size_t>(nT) * nP, 0.0), expected(observed.size(), 0.0);
    PCG32 rng(opt.seed, 0x5bd1e995ULL);
    int produced = 0;
    for (int i = 0; i < opt.sampleCount; ++i) {
        Vec3 d;
        if (!sample(rng, d)) continue;
        if (!d.isFinite() || std::abs(d.length() - 1.0) > 1e-4) {
            Chi2Result r;
            std::ostringstream os;
            os << "sampler returned a non-unit or non-finite direction " << d;
            r.report = os.str();
            return r;
        }
        ++produced;
        const double z = clamp(d.z, -1.0, 1.0);
        double phi = std::atan2(d.y, d.x);
        if (phi < 0) phi += 2 * kPi;
        const int t = std::min(nT - 1, static_cast<int>((z + 1.0) * 0.5 * nT));
        const int p = std::min(nP - 1, static_cast<int>(phi / (2 * kPi) * nP));
        observed[static_cast<size_t>(t) * nP + p] += 1.0;
    }
    // Integrate the pdf over each bin with composite Simpson in (cos theta, phi): dω = dz dphi. The end
    // nodes sit a hair inside the bin, so that a density with a support edge on a bin boundary
    // (hemispheres, cones) is not smeared into the neighbouring bin.
    const int res = opt.integrationRes;
    const double inset = 1e-9;
    double total = 0;
    for (int t = 0; t < nT; ++t) {
        const double z0 = -1.0 + 2.0 * t / nT, dz = 2.0 / nT / res;
        for (int p = 0; p < nP; ++p) {
            const double p0 = 2 * kPi * p / nP, dp = 2 * kPi / nP / res;
            double acc = 0;
            for (int i = 0; i <= res; ++i) {
                const double wi = (i == 0 || i == res) ? 1 : (i % 2 ? 4 : 2);
                const double zi = z0 + i * dz + (i == 0 ? inset : (i == res ? -inset : 0.0));
                const double z = clamp(zi, -1.0, 1.0), r = safeSqrt(1 - z * z);
                for (int j = 0; j <= res; ++j) {
                    const double wj = (j == 0 || j == res) ? 1 : (j % 2 ? 4 : 2);
                    const double phi = p0 + j * dp + (j == 0 ? inset : (j == res ? -inset : 0.0));
                    acc += wi * wj * pdf(Vec3(r * std::cos(phi), r * std::sin(phi), z));
                }
            }
            const double integral = acc * dz * dp / 9.0;
            expected[static_cast<size_t>(t) * nP + p] = integral * opt.sampleCount;
            total += integral;
        }
    }
    Chi2Result r = chi2Histogram(observed, expected, opt.significance, opt.testCount);
    r.sampledMass = static_cast<double>(produced) / opt.sampleCount;
    r.integratedMass = total;
    std::ostringstream os;
    os << r.report << "; sampled mass " << r.sampledMass << ", integrated pdf mass " << total;
    r.report = os.str();
    return r;
}

}  // namespace pf::test
