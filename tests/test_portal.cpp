// Portals and the portal-based path perturbation (Otsu, Hanika & Dachsbacher; ALGORITHMS.md §7.2, §9.3;
// SMS_PORTAL_NOTES.md §2.5):
//
// * portals are read from the scene file and are invisible to rays and shadow rays (bad portals: the
//   bad-input corpus, tests/bad_scenes/portal_*.xml);
// * the density the perturbation reports is its sampler's: the area density of the new x_{i+1}, 1 / |det J|
//   with J the finite-difference Jacobian of its surface coordinates with respect to the two numbers the
//   move draws, converted to T(x -> y) through the line measure with the crossing point fixed
//   (T = p(x_{i+1}) |p - x_{i+1}|^2 cos(x_i) / (|x_i - x_{i+1}|^2 |cos theta_p|), portal_perturbation.h);
// * the paper's mixture of mutations (detailed balance with the core's acceptance on random paths of the
//   portal scenes: test_detailed_balance), and T(y -> x) = 0 exactly when y's first portal crossing is not x's;
// * stationarity: chains of portal moves alone keep the target's distribution of the crossing angle behind
//   a tilted portal (chi-square). Without the |cos theta_p| factor of T this test fails (README: the
//   figures);
// * mlt with the portal perturbation agrees with BDPT and with mlt without it on the three portal scenes, and
//   erpt with the portal perturbation alone with BDPT.
#include <gtest/gtest.h>

#include <cmath>

#include "mcmc/metropolis.h"
#include "path/path_chain.h"
#include "path/portal_perturbation.h"
#include "render/image_task.h"
#include "scene/scene.h"
#include "support/chi2.h"
#include "test_path_helpers.h"
#include "test_portal_common.h"

namespace pf::test {
namespace {

constexpr int kResolution = 16;
constexpr double kR1 = 1.0 / 256, kR2 = 1.0 / 16;

// The three-plane toy with `portals` (rectangle shapes) in place of its own, for the loader tests.
std::unique_ptr<Scene> toyWithPortals(const std::string &portals, const std::string &name) {
    const std::string xml = R"(<scene version="0.6.0">
    <sensor type="perspective"><float name="fov" value="70"/>
        <transform name="toWorld"><lookat origin="3.5, 1.2, 3.5" target="0, 0.6, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <shape type="rectangle"><transform name="toWorld"><rotate x="1" angle="90"/><translate y="4"/></transform>
        <emitter type="area"><rgb name="radiance" value="20, 20, 20"/></emitter></shape>
    <shape type="rectangle"><transform name="toWorld"><scale x="4" y="4"/><rotate x="1" angle="-90"/></transform>
    </shape>)" + portals + "</scene>";
    return loadScene(writeFile(tempDir("portal-" + name), "scene.xml", xml));
}

TEST(Portals, ParsedAndInvisibleToRays) {
    const std::string portal = R"(<shape type="rectangle"><boolean name="portal" value="true"/>
        <transform name="toWorld"><scale x="0.5" y="0.5"/><rotate x="1" angle="-90"/><translate y="2"/></transform>
        </shape>)";
    const std::string tilted = R"(<shape type="rectangle"><boolean name="portal" value="true"/>
        <transform name="toWorld"><rotate x="1" angle="-50"/><translate y="3"/></transform></shape>)";
    auto scene = toyWithPortals(portal + tilted, "two");
    ASSERT_EQ(scene->portals().size(), 2u);
    EXPECT_EQ(scene->shapes().size(), 2u) << "portals are not geometry";
    EXPECT_NEAR(scene->portals()[0]->area(), 1.0, 1e-12);
    EXPECT_NEAR(std::abs(scene->portals()[0]->normal().y), 1.0, 1e-12);
    // A ray down through both portals reaches the floor, and nothing blocks the segment through them.
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(0.1, 3.5, 0.1), Vec3(0, -1, 0)), its));
    EXPECT_NEAR(its.p.y, 0.0, 1e-6);
    EXPECT_FALSE(scene->occluded(Ray(Vec3(0.1, 3.5, 0.1), Vec3(0, -1, 0), 0, 3.4)));
    // The portals themselves are crossed where the geometry says.
    EXPECT_NEAR(scene->portals()[0]->intersect(Ray(Vec3(0.1, 3.5, 0.1), Vec3(0, -1, 0))), 1.5, 1e-12);
    EXPECT_LT(scene->portals()[0]->intersect(Ray(Vec3(0.6, 3.5, 0.1), Vec3(0, -1, 0))), 0.0);
    EXPECT_GT(scene->portals()[1]->intersect(Ray(Vec3(0.1, 3.5, 0.1), Vec3(0, -1, 0))), 0.0);
    // portal=false is an ordinary rectangle.
    auto plain = toyWithPortals(R"(<shape type="rectangle"><boolean name="portal" value="false"/></shape>)", "plain");
    EXPECT_TRUE(plain->portals().empty());
    EXPECT_EQ(plain->shapes().size(), 3u);
}

TEST(Portals, TheShippedScenesHaveTheirPortals) {
    for (const std::string name : {"portal-toy", "portal-box", "cornell-box-portal"})
        EXPECT_EQ(loadMLTTestScene(name, 8, 1)->portals().size(), 1u) << name;
}

std::unique_ptr<Scene> testScene(const std::string &name) { return loadMLTTestScene(name, kResolution, 4); }

// Random current paths of a portal scene that the portal perturbation applies to: BDPT's.
std::vector<MutablePath> portalPaths(const Scene &scene, const Mutation &mutation, size_t count) {
    std::vector<MutablePath> paths;
    for (const MutablePath &x : bdptPaths(scene, 20 * count, kResolution))
        if (paths.size() < count && mutation.applies(x)) paths.push_back(x);
    return paths;
}

class PortalDensity : public ::testing::TestWithParam<std::string> {};

// The area density of the new x_{i+1} by finite differences of the sampler, converted to T(x -> y) through
// the line measure (see the top of the file), against the reported T(x -> y).
TEST_P(PortalDensity, MatchesFiniteDifferencesOfTheSampler) {
    auto scene = testScene(GetParam());
    const PortalPerturbation mutation(*scene, kR1, kR2);
    int checked = 0;
    double worst = 0;
    for (const MutablePath &x : portalPaths(*scene, mutation, 200)) {
        if (checked >= 60) break;
        ReplaySampler sampler({}, 1000 + static_cast<uint64_t>(checked) * 7919 + x.length());
        MutablePath y;
        MutationRecord record;
        if (!mutation.sample(*scene, sampler, x, y, record) || !(chainContribution(*scene, y).luminance() > 0))
            continue;
        const PortalCrossing crossing = firstPortalCrossing(*scene, x);
        const int i = crossing.edge;
        const PathVertex &a = y.vertex(i), &b = y.vertex(i + 1);
        const Frame frame(b.its.n);
        const double h = 1e-7;
        double jacobian[2][2];
        bool smooth = true;
        for (int j = 0; j < 2 && smooth; ++j) {
            Vec3 ends[2];
            for (int side = 0; side < 2 && smooth; ++side) {
                std::vector<double> u = sampler.numbers();
                u[static_cast<size_t>(j)] += side == 0 ? h : -h;
                ReplaySampler replay(u);
                MutablePath z;
                MutationRecord r;
                smooth = mutation.sample(*scene, replay, x, z, r) && z.vertex(i + 1).its.shape == b.its.shape;
                if (smooth) ends[side] = z.vertex(i + 1).position();
            }
            if (!smooth) break;
            const Vec3 d = (ends[0] - ends[1]) / (2 * h);
            jacobian[0][j] = dot(d, frame.s);
            jacobian[1][j] = dot(d, frame.t);
        }
        // Vertices near the crossing point or an edge of their surface are left to other paths.
        if (!smooth || (b.position() - crossing.point).length() < 1e-3) continue;
        const double det = std::abs(jacobian[0][0] * jacobian[1][1] - jacobian[0][1] * jacobian[1][0]);
        const Vec3 w = normalize(b.position() - a.position());
        const double cosPortal = std::abs(dot(w, scene->portals()[static_cast<size_t>(crossing.portal)]->normal()));
        const double fromSampler = (1 / det) * (b.position() - crossing.point).lengthSquared() * a.cosine(w) /
                                   ((b.position() - a.position()).lengthSquared() * cosPortal);
        const double relative = std::abs(mutation.density(*scene, x, y, record) / fromSampler - 1);
        worst = std::max(worst, relative);
        EXPECT_LT(relative, 2e-3) << "path " << checked;
        ++checked;
    }
    std::printf("%s portal: %d Jacobians, worst relative difference %.2g\n", GetParam().c_str(), checked, worst);
    EXPECT_GE(checked, 20) << "too few proposals checked";
}

INSTANTIATE_TEST_SUITE_P(Scenes, PortalDensity, ::testing::Values("portal-toy", "portal-box", "cornell-box-portal"),
                         [](const auto &info) { return gtestName(info.param); });

// The paper's mixture (§5): with portals the bidirectional mutation weighs as much as the lens and portal
// perturbations together, and the selection probabilities, which T includes, follow the weights.
TEST(PortalMixture, PaperWeights) {
    auto scene = testScene("portal-toy");
    const auto integrator = makeTestIntegrator(*scene, "mlt",
                                               {{"lensSubpathMutation", "false"},
                                                {"causticPerturbation", "false"},
                                                {"multiChainPerturbation", "false"},
                                                {"portalPerturbation", "true"}});
    const MutationSet set = dynamic_cast<const PathSpaceIntegrator &>(*integrator).mutations(*scene);
    ASSERT_EQ(set.size(), 3u);
    ASSERT_EQ(set[2].type(), MutationType::Portal);
    int all = 0;
    for (const MutablePath &x : bdptPaths(*scene, 400, kResolution)) {
        if (!set[0].applies(x) || !set[1].applies(x) || !set[2].applies(x)) continue;
        ++all;
        EXPECT_NEAR(set.selectionProbability(x, 0), 0.5, 1e-12);
        EXPECT_NEAR(set.selectionProbability(x, 1), 0.25, 1e-12);
        EXPECT_NEAR(set.selectionProbability(x, 2), 0.25, 1e-12);
        int picked[3] = {0, 0, 0};
        for (int k = 0; k < 1000; ++k) ++picked[set.select(x, (k + 0.5) / 1000)];
        EXPECT_EQ(picked[0], 500);
        EXPECT_EQ(picked[2], 250);
    }
    EXPECT_GT(all, 10);
    // Without portals the mutations are equally likely, as before.
    auto plain = testScene("cornell-box");
    const MutationSet equal = dynamic_cast<const PathSpaceIntegrator &>(*integrator).mutations(*plain);
    for (const MutablePath &x : bdptPaths(*plain, 50, kResolution))
        if (equal[0].applies(x) && equal[1].applies(x)) {
            EXPECT_NEAR(equal.selectionProbability(x, 0), 0.5, 1e-12);
        }
}

// The toy with a large light and a portal tilted by 50 degrees in its hole (SMS_PORTAL_NOTES.md §2.5).
std::unique_ptr<Scene> tiltedToy() {
    std::string xml = R"(<scene version="0.6.0">
    <sensor type="perspective"><float name="fov" value="90"/>
        <transform name="toWorld"><lookat origin="0, 1.2, 3.9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film>
    </sensor>
    <shape type="rectangle"><transform name="toWorld"><scale x="2.5" y="2.5"/><rotate x="1" angle="90"/>
        <translate y="4"/></transform><emitter type="area"><rgb name="radiance" value="1, 1, 1"/></emitter></shape>
    <shape type="rectangle"><transform name="toWorld"><scale x="4" y="4"/><rotate x="1" angle="-90"/></transform>
    </shape>
    <shape type="rectangle"><boolean name="portal" value="true"/>
        <transform name="toWorld"><scale x="0.7" y="0.7"/><rotate x="1" angle="-90"/><rotate z="1" angle="50"/>
        <translate y="2"/></transform></shape>)";
    // The occluder: a 8 x 8 plane at y = 2 with a hole of 1 x 1 in the middle, diffuse on both sides.
    for (const char *strip :
         {"<scale x=\"1.75\" y=\"4\"/><rotate x=\"1\" angle=\"-90\"/><translate x=\"2.25\" y=\"2\"/>",
          "<scale x=\"1.75\" y=\"4\"/><rotate x=\"1\" angle=\"-90\"/><translate x=\"-2.25\" y=\"2\"/>",
          "<scale x=\"0.5\" y=\"1.75\"/><rotate x=\"1\" angle=\"-90\"/><translate y=\"2\" z=\"2.25\"/>",
          "<scale x=\"0.5\" y=\"1.75\"/><rotate x=\"1\" angle=\"-90\"/><translate y=\"2\" z=\"-2.25\"/>"})
        xml += std::string("<shape type=\"rectangle\"><transform name=\"toWorld\">") + strip +
               "</transform><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></shape>";
    return loadScene(writeFile(tempDir("portal-tilted"), "scene.xml", xml + "</scene>"));
}

// Chains of portal moves alone keep the crossing point p fixed, so their target on the directions w through
// p is pi(w) = f(y(w)) |cos theta_p| / G(y(w)) per unit solid angle (portal_perturbation.h). Independent
// chains are started from pi (resampled from uniform directions) and run 60 steps with large turns (up to
// 0.5 radians); the histogram of |cos theta_p| of their final states must be pi's.
TEST(PortalStationarity, CrossingAngleKeepsTheTarget) {
    auto scene = tiltedToy();
    const PortalPerturbation mutation(*scene, 0.02, 0.5);
    // A light -> floor -> camera path through the portal, whose crossing point all chains share.
    MutablePath x;
    for (const MutablePath &path : bdptPaths(*scene, 4000, kResolution))
        if (path.length() == 3 && mutation.applies(path)) {
            x = path;
            break;
        }
    ASSERT_EQ(x.length(), 3);
    const PortalCrossing crossing = firstPortalCrossing(*scene, x);
    const Vec3 normal = scene->portals()[0]->normal();
    constexpr int kBins = 12;
    const auto bin = [&](const PathView &y) {
        const Vec3 w = normalize(y.vertex(1).position() - y.vertex(0).position());
        return std::min(kBins - 1, static_cast<int>(std::abs(dot(w, normal)) * kBins));
    };
    // pi over a stratified grid of directions w pointing down (the light is above): each cell's weight is
    // pi(w) times its solid angle, the same for all cells.
    std::vector<double> expected(kBins, 0.0);
    std::vector<std::pair<double, MutablePath>> starts;
    const int grid = 500;
    PCG32 rng(3, 5);
    IndependentSampler unused(1, 0, 0);
    double total = 0;
    for (int a = 0; a < grid; ++a)
        for (int b = 0; b < grid; ++b) {
            const double cosTheta = -(a + rng.nextDouble()) / grid, phi = 2 * kPi * (b + rng.nextDouble()) / grid;
            const double sinTheta = std::sqrt(1 - cosTheta * cosTheta);
            const Vec3 w(sinTheta * std::cos(phi), cosTheta, sinTheta * std::sin(phi));
            MutablePath y;
            if (!mutation.turn(*scene, unused, x, crossing, w, y)) continue;
            const PortalCrossing c = firstPortalCrossing(*scene, y);
            if (c.edge != 0 || (c.point - crossing.point).length() > 1e-6) continue;
            const double g = y.vertex(0).cosine(w) * y.vertex(1).cosine(w) /
                             (y.vertex(1).position() - y.vertex(0).position()).lengthSquared();
            const double pi = chainContribution(*scene, y).luminance() * std::abs(dot(w, normal)) / g;
            if (!(pi > 0)) continue;
            expected[static_cast<size_t>(bin(y))] += pi;
            total += pi;
            starts.emplace_back(total, y);
        }
    ASSERT_GT(starts.size(), 1000u);
    MutationSet set;
    set.add(std::make_unique<PortalPerturbation>(*scene, 0.02, 0.5));
    ImageBlock film = makeFilmBlock(*scene);
    MutationCounts counts = PathChain::mutationTypes({MutationType::Portal});
    const int chains = 6000;
    std::vector<double> observed(kBins, 0.0);
    for (int k = 0; k < chains; ++k) {
        const double u = rng.nextDouble() * total;
        const auto it =
            std::lower_bound(starts.begin(), starts.end(), u, [](const auto &s, double v) { return s.first < v; });
        PathChain chain(*scene, set, 2, 3, film, 1.0);
        ASSERT_GT(chain.start(it->second), 0.0);
        runMetropolis(chain, 60, rng, nullptr, counts);
        observed[static_cast<size_t>(bin(chain.current()))] += 1;
    }
    for (double &e : expected) e *= chains / total;
    const Chi2Result r = chi2Histogram(observed, expected, 0.01);
    std::printf("portal stationarity: %d chains, acceptance %.3f, chi2 %.1f with %d dof, p = %.3g\n", chains,
                static_cast<double>(counts[0].accepted) / std::max<uint64_t>(1, counts[0].proposed), r.statistic, r.dof,
                r.pValue);
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_GT(counts[0].accepted, static_cast<uint64_t>(chains) * 20) << "the chains must move to show a bias";
}

// mlt with the portal perturbation (the paper's mixture) agrees with BDPT and with mlt without it: block means
// over independent renders (test_long_portal: larger, longer paths, more renders).
struct ConvergenceCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const ConvergenceCase &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int maxDepth, mutationsPerPixel, renders;
};

class PortalConvergence : public ::testing::TestWithParam<ConvergenceCase> {};

TEST_P(PortalConvergence, AgreesWithBDPTAndWithoutPortal) {
    ConvergenceSetup s;
    s.budget = GetParam().mutationsPerPixel;
    s.seeds = GetParam().renders;
    s.referenceSpp = 128;
    s.maxDepth = GetParam().maxDepth;
    // The whole image's luminance of an mlt render is its normalization, so its error is the seeding's alone:
    // with 8192 luminance samples it came to 3.3% of portal-toy's mean with one draw of seed paths, over the 3%
    // that the comparison needs; with 16384 it came to 2.0%.
    expectPortalConvergence(GetParam().scene, s, 16384);
}

// Paths of up to 3 edges; in the box, whose light comes through its small opening, of up to 2 (the light
// through the opening seen directly) and with more mutations and renders, which the short test can resolve.
INSTANTIATE_TEST_SUITE_P(Scenes, PortalConvergence,
                         ::testing::Values(ConvergenceCase{"portal-toy", 3, 256, 16},
                                           ConvergenceCase{"portal-box", 2, 1024, 24},
                                           ConvergenceCase{"cornell-box-portal", 3, 256, 16}),
                         [](const auto &info) { return gtestName(info.param.scene); });

// The tilted portal reaches below the occluder, so turning a path's crossing edge (light -> floor) can make
// its next edge (floor -> the occluder's underside) cross the portal first: then the reverse move would
// turn that edge, T(y -> x) = 0, and the chain rejects (the reference code accepts such moves).
TEST(PortalReverse, ExistsOnlyIfTheFirstCrossingIsTheSame) {
    auto scene = tiltedToy();
    const PortalPerturbation mutation(*scene, 0.02, 0.5);
    int same = 0, other = 0;
    uint64_t k = 0;
    for (const MutablePath &x : bdptPaths(*scene, 6000, kResolution)) {
        if (x.length() != 4 || !mutation.applies(x)) continue;
        for (int j = 0; j < 24; ++j) {
            IndependentSampler sampler(7, k++, 0);
            MutablePath y;
            MutationRecord record;
            if (!mutation.sample(*scene, sampler, x, y, record) || !(chainContribution(*scene, y).luminance() > 0))
                continue;
            const PortalCrossing cx = firstPortalCrossing(*scene, x), cy = firstPortalCrossing(*scene, y);
            EXPECT_GT(mutation.density(*scene, x, y, record), 0.0) << "the forward move was made";
            const double reverse = mutation.density(*scene, y, x, record.reverse());
            if (cy.edge == cx.edge) {
                ++same;
                EXPECT_GT(reverse, 0.0);
            } else {
                ++other;
                EXPECT_EQ(reverse, 0.0) << "y crosses first on edge " << cy.edge << ", x on " << cx.edge;
            }
        }
    }
    std::printf("portal reverse moves: %d with the same first crossing, %d crossing first elsewhere\n", same, other);
    EXPECT_GE(same, 50);
    EXPECT_GE(other, 5) << "the case must occur for the test to mean anything";
}

// ERPT needs no ergodicity (ALGORITHMS.md §5.2): bursts of portal moves alone, which keep each seed's crossing
// point, must leave the image unbiased, a check of the perturbation's acceptance on its own.
TEST(PortalBursts, ERPTWithThePortalPerturbationAloneAgreesWithBDPT) {
    ConvergenceSetup s;
    s.maxDepth = 3;
    expectSingleMutationConvergence("cornell-box-portal", MutationType::Portal, s);
}

}  // namespace
}  // namespace pf::test
