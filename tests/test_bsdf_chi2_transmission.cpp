// Chi-square goodness of fit of sample() against pdf() for roughdielectric: all distributions and
// roughness values, isotropic and anisotropic, from outside and from inside (beyond the critical
// angle too), visible and all normals, in both transport modes.
#include <cstdio>

#include "test_bsdf_common.h"

namespace pf::test {
namespace {

constexpr int kSamples = 200000;
const char *kDistributions[] = {"beckmann", "ggx", "phong"};
constexpr double kAlphas[] = {0.05, 0.2, 0.6};

TransportMode alternate(size_t i) { return i % 2 ? TransportMode::Importance : TransportMode::Radiance; }

std::string label(const char *fmt, const std::string &a, double x, double theta) {
    char buf[160];
    std::snprintf(buf, sizeof buf, fmt, a.c_str(), x, theta);
    return buf;
}

TEST(BSDFChi2Transmission, RoughDielectric) {
    std::vector<Chi2Case> cases;
    for (const char *dist : kDistributions) {
        for (double alpha : kAlphas) {
            const auto iso = makeBSDF("roughdielectric", {{"distribution", dist}, {"alpha", alpha}});
            const auto aniso =
                makeBSDF("roughdielectric", {{"distribution", dist}, {"alphaU", alpha}, {"alphaV", 2.5 * alpha}});
            // Outside: normal, oblique, grazing. Inside: below and beyond the critical angle (41.6 deg).
            for (double theta : {0.0, 50.0, 85.0, 160.0, 120.0})
                cases.push_back({label("roughdielectric %s alpha %g theta %g", dist, alpha, theta), iso,
                                 direction(theta, 0), alternate(cases.size()), binAngleFor(alpha)});
            cases.push_back({label("roughdielectric %s alphaU %g (alphaV 2.5x) theta %g", dist, alpha, 40), aniso,
                             direction(40, 30), alternate(cases.size()), binAngleFor(alpha)});
            cases.push_back({label("roughdielectric %s alphaU %g (alphaV 2.5x) theta %g", dist, alpha, 130), aniso,
                             direction(130, 200), alternate(cases.size()), binAngleFor(alpha)});
        }
    }
    for (const char *dist : {"beckmann", "ggx"}) {
        const auto bsdf =
            makeBSDF("roughdielectric", {{"distribution", dist}, {"alpha", 0.2}, {"sampleVisible", false}});
        for (double theta : {50.0, 160.0})
            cases.push_back({label("roughdielectric %s all normals alpha %g theta %g", dist, 0.2, theta), bsdf,
                             direction(theta, 0), alternate(cases.size()), binAngleFor(0.2)});
    }
    expectChi2(cases, kSamples);
}

}  // namespace
}  // namespace pf::test
