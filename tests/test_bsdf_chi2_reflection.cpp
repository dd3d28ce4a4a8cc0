// Chi-square goodness of fit of sample() against pdf() for the reflection models: diffuse,
// roughconductor (Beckmann, GGX, Phong; isotropic and anisotropic; visible and all normals), ward,
// twosided, mask, bumpmap and the smooth lobes of plastic and roughplastic. Incident directions include normal, oblique
// and grazing (85 degrees) incidence and, for twosided, the back side.
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

TEST(BSDFChi2Reflection, Diffuse) {
    std::vector<Chi2Case> cases;
    for (double theta : {0.0, 45.0, 85.0})
        cases.push_back({label("diffuse %s%g theta %g", "", 0, theta), makeBSDF("diffuse"), direction(theta, 30),
                         alternate(cases.size())});
    expectChi2(cases, kSamples);
}

TEST(BSDFChi2Reflection, RoughConductor) {
    std::vector<Chi2Case> cases;
    for (const char *dist : kDistributions) {
        for (double alpha : kAlphas) {
            const auto iso = makeBSDF("roughconductor", {{"distribution", dist}, {"alpha", alpha}});
            const auto aniso =
                makeBSDF("roughconductor", {{"distribution", dist}, {"alphaU", alpha}, {"alphaV", 2.5 * alpha}});
            for (double theta : {0.0, 50.0, 85.0})
                cases.push_back({label("roughconductor %s alpha %g theta %g", dist, alpha, theta), iso,
                                 direction(theta, 0), alternate(cases.size()), binAngleFor(alpha)});
            for (double theta : {35.0, 85.0})
                cases.push_back({label("roughconductor %s alphaU %g (alphaV 2.5x) theta %g", dist, alpha, theta), aniso,
                                 direction(theta, theta == 35.0 ? 40 : 120), alternate(cases.size()),
                                 binAngleFor(alpha)});
        }
    }
    // Sampling all normals instead of the visible ones (Mitsuba's sampleVisible = false).
    for (const char *dist : {"beckmann", "ggx"}) {
        const auto iso = makeBSDF("roughconductor", {{"distribution", dist}, {"alpha", 0.2}, {"sampleVisible", false}});
        const auto aniso = makeBSDF(
            "roughconductor", {{"distribution", dist}, {"alphaU", 0.3}, {"alphaV", 0.1}, {"sampleVisible", false}});
        cases.push_back({label("roughconductor %s all normals alpha %g theta %g", dist, 0.2, 50), iso, direction(50, 0),
                         alternate(cases.size()), binAngleFor(0.2)});
        cases.push_back({label("roughconductor %s all normals alphaU %g theta %g", dist, 0.3, 85), aniso,
                         direction(85, 200), alternate(cases.size()), binAngleFor(0.1)});
    }
    expectChi2(cases, kSamples);
}

TEST(BSDFChi2Reflection, Ward) {
    std::vector<Chi2Case> cases;
    for (const char *variant : {"ward", "ward-duer", "balanced"}) {
        const auto iso = makeBSDF("ward", {{"variant", variant}, {"alphaU", 0.1}, {"alphaV", 0.1}});
        const auto aniso = makeBSDF("ward", {{"variant", variant}, {"alphaU", 0.1}, {"alphaV", 0.35}});
        cases.push_back({label("ward %s iso alpha %g theta %g", variant, 0.1, 30), iso, direction(30, 10),
                         alternate(cases.size()), binAngleFor(0.1)});
        cases.push_back({label("ward %s aniso alphaU %g theta %g", variant, 0.1, 80), aniso, direction(80, 70),
                         alternate(cases.size()), binAngleFor(0.1)});
    }
    expectChi2(cases, kSamples);
}

TEST(BSDFChi2Reflection, Adapters) {
    const auto glossy = makeBSDF("roughconductor", {{"distribution", "ggx"}, {"alpha", 0.2}});
    const auto twosided = makeBSDF("twosided", {}, {nested(glossy)});
    const auto twoMaterials = makeBSDF("twosided", {}, {nested(makeBSDF("diffuse")), nested(glossy)});
    const auto mask = makeBSDF("mask", {{"opacity", 0.3}}, {nested(glossy)});
    const auto bumpGlossy =
        makeBSDF("bumpmap", {}, {nested(glossy), {"", ObjectKind::Texture, std::make_shared<LinearHeight>(0.3, -0.2)}});
    const auto bumpDiffuse =
        makeBSDF("bumpmap", {},
                 {nested(makeBSDF("diffuse")), {"", ObjectKind::Texture, std::make_shared<LinearHeight>(0.5, 0.4)}});
    const double bin = binAngleFor(0.2);
    const std::vector<Chi2Case> cases = {
        {"twosided roughconductor front", twosided, direction(40, 20), TransportMode::Radiance, bin},
        {"twosided roughconductor back", twosided, direction(140, 20), TransportMode::Importance, bin},
        {"twosided diffuse/roughconductor front", twoMaterials, direction(60, 0), TransportMode::Radiance, bin},
        {"twosided diffuse/roughconductor back", twoMaterials, direction(120, 0), TransportMode::Importance, bin},
        {"mask 0.3 roughconductor", mask, direction(30, 0), TransportMode::Radiance, bin},
        {"bumpmap roughconductor", bumpGlossy, direction(40, 90), TransportMode::Importance, bin},
        {"bumpmap diffuse", bumpDiffuse, direction(70, 45), TransportMode::Radiance, 0.15},
    };
    expectChi2(cases, kSamples);
}

TEST(BSDFChi2Reflection, Plastic) {
    std::vector<Chi2Case> cases;
    const auto plastic = makeBSDF("plastic", {{"diffuseReflectance", Spectrum(0.2, 0.5, 0.8)}});
    for (double theta : {0.0, 60.0, 85.0})
        cases.push_back(
            {label("plastic%s %g theta %g", "", 0, theta), plastic, direction(theta, 0), alternate(cases.size())});
    for (const char *dist : kDistributions) {
        for (double alpha : kAlphas) {
            const auto bsdf = makeBSDF("roughplastic", {{"distribution", dist}, {"alpha", alpha}});
            for (double theta : {30.0, 85.0})
                cases.push_back({label("roughplastic %s alpha %g theta %g", dist, alpha, theta), bsdf,
                                 direction(theta, 0), alternate(cases.size()), binAngleFor(alpha)});
        }
    }
    expectChi2(cases, kSamples);
}

}  // namespace
}  // namespace pf::test
