// Specular manifold sampling (manifold/sms.h, integrators/sms_connection.h; ALGORITHMS.md §7.1, §9.3;
// SMS_PORTAL_NOTES.md §1.6): the constraint's derivatives against finite differences (both forms, the azimuth
// wrap), the geometry term against a traced bundle and the plane mirror's closed form, the estimators' counting
// property (unbiased mean = number of solutions, biased at most that and rising with M), closed forms for a
// plane mirror and a flat refracting interface under a point light, and parameter checking.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "bsdf/fresnel.h"
#include "core/rng.h"
#include "integrators/sms_connection.h"
#include "manifold/sms.h"
#include "scene/scene.h"
#include "support/agreement.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

double uniform(PCG32 &rng, double lo, double hi) { return lo + (hi - lo) * rng.nextDouble(); }

Vec3 randomUnit(PCG32 &rng) {
    const double z = uniform(rng, -1, 1), phi = uniform(rng, 0, 2 * kPi), r = std::sqrt(1 - z * z);
    return {r * std::cos(phi), r * std::sin(phi), z};
}

// A caster vertex with a random orthonormal chart, a shading normal tilted off the geometric one and random
// normal derivatives (tangent to the normal).
ManifoldVertex randomVertex(PCG32 &rng, Scattering scattering, double eta) {
    ManifoldVertex v;
    v.p = Vec3(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2));
    v.ng = Vec3(0, 0, 1);
    v.n = normalize(Vec3(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), 1));
    const double a = uniform(rng, 0, 2 * kPi);
    v.dpdu = Vec3(std::cos(a), std::sin(a), 0);
    v.dpdv = Vec3(-std::sin(a), std::cos(a), 0);
    const auto tangent = [&](const Vec3 &w) { return w - v.n * dot(w, v.n); };
    v.dndu = tangent(Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)));
    v.dndv = tangent(Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)));
    v.scattering = scattering;
    v.eta = eta;
    return v;
}

// The vertex moved to chart coordinates (u, v) under the first-order model of §6.2.
ManifoldVertex moved(const ManifoldVertex &v0, double u, double v) {
    ManifoldVertex x = v0;
    x.p = v0.p + v0.dpdu * u + v0.dpdv * v;
    x.n = normalize(v0.n + v0.dndu * u + v0.dndv * v);
    return x;
}

// Central differences of a constraint form against its analytic (angle: dual-number) derivative.
template <typename F>
void expectDerivativeMatches(const F &constraint, const ManifoldVertex &v, const std::string &what) {
    const std::optional<ConstraintJet> jet = constraint(v);
    ASSERT_TRUE(jet) << what;
    const double h = 1e-6;
    for (int k = 0; k < 2; ++k) {
        const auto plus = constraint(moved(v, k == 0 ? h : 0, k == 1 ? h : 0));
        const auto minus = constraint(moved(v, k == 0 ? -h : 0, k == 1 ? -h : 0));
        ASSERT_TRUE(plus && minus) << what;
        const Vec2 fd = (plus->value - minus->value) * (0.5 / h);
        const double scale = 1 + std::abs(jet->derivative(0, k)) + std::abs(jet->derivative(1, k));
        EXPECT_NEAR(fd.x, jet->derivative(0, k), 1e-6 * scale) << what << " column " << k;
        EXPECT_NEAR(fd.y, jet->derivative(1, k), 1e-6 * scale) << what << " column " << k;
    }
}

// The i-th random vertex of the derivative tests: reflections and refractions (eta 1.5 and 1 / 1.33) in turn.
ManifoldVertex randomCaster(PCG32 &rng, int i) {
    const bool refraction = i % 2 == 1;
    return randomVertex(rng, refraction ? Scattering::Refraction : Scattering::Reflection,
                        refraction ? (i % 4 == 1 ? 1.5 : 1 / 1.33) : 1.0);
}

TEST(SmsConstraint, DerivativesMatchFiniteDifferences) {
    PCG32 rng(5, 7);
    int tested = 0;
    for (int i = 0; i < 400; ++i) {
        const ManifoldVertex v = randomCaster(rng, i);
        const Vec3 a = v.p + randomUnit(rng) * uniform(rng, 0.5, 3);
        const Vec3 b = v.p + randomUnit(rng) * uniform(rng, 0.5, 3);
        // A frame fixed for the differences (the solver's default frame follows the configuration).
        const Frame frame(randomUnit(rng));
        const auto angle = [&](const ManifoldVertex &x) { return angleDifferenceConstraint(a, x, b, &frame); };
        const auto half = [&](const ManifoldVertex &x) { return halfVectorConstraint(a, x, b); };
        const std::optional<ConstraintJet> jet = angle(v);
        // Skip configurations within 1e-3 of a frame pole or of the TIR switch, where differences are
        // ill-conditioned.
        if (!jet || !half(v) || std::abs(jet->derivative.frobeniusNormSquared()) > 1e6) continue;
        bool nearSwitch = false;
        for (double h : {-1e-5, 1e-5})
            for (int k = 0; k < 2; ++k) {
                const auto p = angle(moved(v, k == 0 ? h : 0, k == 1 ? h : 0));
                nearSwitch = nearSwitch || !p || std::abs(p->value.x - jet->value.x) > 1e-3 ||
                             std::abs(p->value.y - jet->value.y) > 1e-3;
            }
        if (nearSwitch) continue;
        expectDerivativeMatches(angle, v, "angle " + std::to_string(i));
        expectDerivativeMatches(half, v, "halfvector " + std::to_string(i));
        ++tested;
    }
    EXPECT_GT(tested, 300);
}

// Near Δφ = ±π in a frame whose -x axis lies between S(ω_i) and ω_o: the wrapped difference is small and
// continuous, and its derivative is still that of the differences.
TEST(SmsConstraint, AzimuthWrapNearPlusMinusPi) {
    ManifoldVertex v;
    v.ng = v.n = Vec3(0, 0, 1);
    v.dpdu = Vec3(1, 0, 0);
    v.dpdv = Vec3(0, 1, 0);
    v.dndu = Vec3(0.3, 0, 0);
    v.dndv = Vec3(0, 0.3, 0);
    v.scattering = Scattering::Reflection;
    // ω_i towards a = (1, 0.01, 1): the mirror direction is (-1, -0.01, 1)/|.|, at φ just below -π + ...; ω_o
    // towards b = (-1, +0.01, 1) at φ just below π.
    const Vec3 a(1, 0.01, 1), b(-1, 0.01, 1);
    const Frame frame(Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1));
    const auto angle = [&](const ManifoldVertex &x) { return angleDifferenceConstraint(a, x, b, &frame); };
    const std::optional<ConstraintJet> jet = angle(v);
    ASSERT_TRUE(jet);
    EXPECT_LT(std::abs(jet->value.y), 0.05) << "Δφ must be wrapped into [-π, π]";
    EXPECT_GT(std::abs(jet->value.y), 1e-3);
    expectDerivativeMatches(angle, v, "wrap");
    // A move along y carries the pair across the wrap: still continuous.
    const auto across = angle(moved(v, 0, 0.02));
    ASSERT_TRUE(across);
    EXPECT_LT(std::abs(across->value.y - jet->value.y), 0.2);
    // Both forms have the same roots: at the mirror configuration both vanish.
    const Vec3 mirrorB(-1, -0.01, 1);
    EXPECT_LT(std::hypot(angleDifferenceConstraint(a, v, mirrorB, &frame)->value.x,
                         angleDifferenceConstraint(a, v, mirrorB, &frame)->value.y),
              1e-12);
    const auto h = halfVectorConstraint(a, v, mirrorB);
    EXPECT_LT(std::hypot(h->value.x, h->value.y), 1e-12);
}

// The off-diagonal blocks of a chain's Newton system (∂C_i with respect to the neighbours' charts, both forms)
// against central differences, the neighbours moved in their charts: the block rows of two-vertex chains.
TEST(SmsConstraint, ChainBlocksMatchFiniteDifferences) {
    PCG32 rng(9, 3);
    int tested = 0;
    for (int i = 0; i < 300; ++i) {
        const ManifoldVertex v = randomCaster(rng, i);
        ManifoldVertex prev = randomCaster(rng, i), next = randomCaster(rng, i);
        prev.p = v.p + randomUnit(rng) * uniform(rng, 0.5, 3);
        next.p = v.p + randomUnit(rng) * uniform(rng, 0.5, 3);
        const Frame frame(randomUnit(rng));
        for (SmsConstraint form : {SmsConstraint::AngleDifference, SmsConstraint::HalfVector}) {
            const std::optional<ChainConstraint> c = chainConstraint(form, prev, v, next, &frame);
            if (!c || c->self.frobeniusNormSquared() > 1e6 || c->prev.frobeniusNormSquared() > 1e6 ||
                c->next.frobeniusNormSquared() > 1e6)
                continue;
            const double h = 1e-6;
            bool smooth = true;  // away from the TIR switch and the frame's poles (as above)
            for (int side = 0; side < 2 && smooth; ++side)
                for (int k = 0; k < 2 && smooth; ++k) {
                    const auto at = [&](double t) {
                        const ManifoldVertex &m = side == 0 ? prev : next;
                        const ManifoldVertex q = moved(m, k == 0 ? t : 0, k == 1 ? t : 0);
                        return side == 0 ? chainConstraint(form, q, v, next, &frame)
                                         : chainConstraint(form, prev, v, q, &frame);
                    };
                    const auto plus = at(h), minus = at(-h), far = at(1e-4);
                    if (!plus || !minus || !far || std::abs(far->value.x - c->value.x) > 1e-2 ||
                        std::abs(far->value.y - c->value.y) > 1e-2) {
                        smooth = false;
                        break;
                    }
                    const Vec2 fd = (plus->value - minus->value) * (0.5 / h);
                    const Mat2 &block = side == 0 ? c->prev : c->next;
                    const double scale = 1 + std::abs(block(0, k)) + std::abs(block(1, k));
                    EXPECT_NEAR(fd.x, block(0, k), 1e-5 * scale) << i << " side " << side << " column " << k;
                    EXPECT_NEAR(fd.y, block(1, k), 1e-5 * scale) << i << " side " << side << " column " << k;
                }
            if (smooth) ++tested;
        }
    }
    EXPECT_GT(tested, 400);
}

// --- Scenes: a diffuse floor (y = 0, normal +y) and one caster; a point light.

std::string floorXml(double y) {
    return R"(<shape type="rectangle"><bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
      <transform name="toWorld"><scale x="50" y="50" z="50"/><rotate x="1" angle="-90"/>
      <translate y=")" +
           std::to_string(y) + R"("/></transform></shape>)";
}

std::string sceneXml(const std::string &casterXml, const Vec3 &light, double floorY = 0) {
    return R"(<scene version="0.6.0"><integrator type="sms"/>
      <sensor type="perspective"><transform name="toWorld"><lookat origin="0, 5, 8" target="0, 0, 0" up="0, 1, 0"/>
      </transform><film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
      <emitter type="point"><point name="position" x=")" +
           std::to_string(light.x) + R"(" y=")" + std::to_string(light.y) + R"(" z=")" + std::to_string(light.z) +
           R"("/><spectrum name="intensity" value="10"/></emitter>)" + floorXml(floorY) + casterXml + "</scene>";
}

// A vertical mirror at x = 2 facing -x.
const std::string kPlaneMirror =
    R"(<shape type="rectangle"><bsdf type="conductor"><string name="material" value="none"/>
  </bsdf><transform name="toWorld"><scale x="4" y="4" z="4"/><rotate y="1" angle="-90"/><translate x="2" y="2"/>
  </transform></shape>)";
// A horizontal glass interface at y = 0 (normal +y, glass below), 6 x 6; the floor is at depth 1 under it. (The
// half-vector form's Newton basins are small for refraction [SMS Fig. 8]: on a far larger plane its seeds almost
// never converge within maxIterations.)
const std::string kGlassPlane = R"(<shape type="rectangle"><bsdf type="dielectric"><float name="intIOR" value="1.5"/>
  <float name="extIOR" value="1"/></bsdf><transform name="toWorld"><scale x="3" y="3" z="3"/>
  <rotate x="1" angle="-90"/></transform></shape>)";
// A mirror sphere of radius 1 at (2, 1.5, 0).
const std::string kMirrorSphere = R"(<shape type="sphere"><point name="center" x="2" y="1.5" z="0"/>
  <float name="radius" value="1"/><bsdf type="conductor"><string name="material" value="none"/></bsdf></shape>)";
// The ring of scenes/ring-caustic: a two-sided gold cylinder of radius 10 and height 4 on the floor.
const std::string kRing = R"(<shape type="cylinder"><bsdf type="twosided"><bsdf type="conductor">
  <string name="material" value="Au"/></bsdf></bsdf><transform name="toWorld"><scale x="10" y="10" z="4"/>
  <rotate x="1" angle="-90"/><rotate y="1" angle="140"/></transform></shape>)";

std::unique_ptr<Scene> load(const std::string &xml) {
    static int counter = 0;
    return loadScene(writeFile(tempDir("sms"), "scene" + std::to_string(counter++) + ".xml", xml));
}

// The receiver point where a ray from `from` straight down meets the floor (its.wi faces up).
Intersection receiverAt(const Scene &scene, const Vec3 &from) {
    Intersection its;
    EXPECT_TRUE(scene.intersect(Ray(from, Vec3(0, -1, 0)), its));
    return its;
}

const Shape &casterOf(const Scene &scene) {
    for (const auto &s : scene.shapes())
        if (specularEvent(*s) != Scattering::None) return *s;
    throw std::runtime_error("no caster");
}

struct Counted {
    MeanCI estimate;
    double maxValue = 0;
};

// manifoldSum with f = 1 per solution at fixed x_1, x_3, over n independent estimates.
Counted countSolutions(const Scene &scene, const Intersection &x1, const Vec3 &x3, SmsSettings settings, int n,
                       int vertices = 1) {
    SmsStatistics stats;
    double sum = 0, sum2 = 0, maxValue = 0;
    for (int i = 0; i < n; ++i) {
        IndependentSampler sampler(11, static_cast<uint64_t>(i), 0);
        const double v =
            manifoldSum(scene, x1, x3, casterOf(scene), vertices, settings, sampler, stats, [](const SpecularChain &) {
                return Spectrum(1.0);
            }).r;
        sum += v;
        sum2 += v * v;
        maxValue = std::max(maxValue, v);
    }
    Counted c;
    c.estimate.mean = sum / n;
    c.estimate.stderr_ = std::sqrt(std::max(0.0, sum2 / n - c.estimate.mean * c.estimate.mean) / (n - 1));
    c.estimate.n = static_cast<size_t>(n);
    c.maxValue = maxValue;
    EXPECT_EQ(stats.guardHits.load(), 0u);
    return c;
}

// The number of distinct solutions found by many trials (biased with a large M, one estimate).
int distinctSolutions(const Scene &scene, const Intersection &x1, const Vec3 &x3, int vertices = 1) {
    SmsSettings s;
    s.biased = true;
    s.trials = 4000;
    IndependentSampler sampler(3, 0, 0);
    SmsStatistics stats;
    return static_cast<int>(
        manifoldSum(scene, x1, x3, casterOf(scene), vertices, s, sampler, stats, [](const SpecularChain &) {
            return Spectrum(1.0);
        }).r);
}

struct CountCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const CountCase &c, std::ostream *os) { *os << c.name; }
    std::string name, caster;
    Vec3 receiverFrom, light;
    double floorY;
    int solutions;  // 0: 2 or 3 (inside the ring), counted by distinctSolutions
};

class SmsCounting : public ::testing::TestWithParam<CountCase> {};

TEST_P(SmsCounting, UnbiasedMeanIsTheNumberOfSolutionsAndBiasedIsAtMostThat) {
    const CountCase &c = GetParam();
    auto scene = load(sceneXml(c.caster, c.light, c.floorY));
    const Intersection x1 = receiverAt(*scene, c.receiverFrom);
    int solutions = distinctSolutions(*scene, x1, c.light);
    if (c.solutions > 0)
        EXPECT_EQ(solutions, c.solutions);
    else
        EXPECT_TRUE(solutions == 2 || solutions == 3) << solutions;
    for (SmsConstraint form : {SmsConstraint::AngleDifference, SmsConstraint::HalfVector}) {
        SmsSettings unbiased;
        unbiased.constraint = form;
        const Counted u = countSolutions(*scene, x1, c.light, unbiased, 4000);
        std::printf("%s, %s: %d solutions, unbiased mean %.4f +- %.4f\n", c.name.c_str(),
                    form == SmsConstraint::AngleDifference ? "angle" : "halfvector", solutions, u.estimate.mean,
                    u.estimate.stderr_);
        EXPECT_NEAR(u.estimate.mean, solutions, 4.5 * u.estimate.stderr_ + 1e-9)
            << c.name << " form " << static_cast<int>(form) << " mean " << u.estimate.mean << " +- "
            << u.estimate.stderr_;
        double previous = 0;
        for (int m : {1, 4, 16}) {
            SmsSettings biased = unbiased;
            biased.biased = true;
            biased.trials = m;
            const Counted b = countSolutions(*scene, x1, c.light, biased, 1000);
            EXPECT_LE(b.maxValue, solutions) << c.name << " M = " << m;
            EXPECT_GE(b.estimate.mean, previous - 4 * b.estimate.stderr_) << c.name << " M = " << m;
            previous = b.estimate.mean;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(
    Casters, SmsCounting,
    ::testing::Values(CountCase{"PlaneMirror", kPlaneMirror, Vec3(0, 1, 0), Vec3(1, 1, 0), 0, 1},
                      CountCase{"RefractingPlane", kGlassPlane, Vec3(0.7, -0.5, 0.2), Vec3(0, 1, 0), -1, 1},
                      CountCase{"ConvexMirrorSphere", kMirrorSphere, Vec3(0, 1, 0), Vec3(1, 3, 1), 0, 1},
                      CountCase{"InsideTheRing", kRing, Vec3(2, 1, 3), Vec3(-5, 3, 2), 0, 0}),
    [](const auto &info) { return info.param.name; });

// A glass sphere (radius 1, centre (0, 2, 0)) over the floor and a point light above it: exactly one chain of two
// refractions (in and out) connects a floor point below the sphere to the light; the unbiased two-vertex estimate
// counts 1, the biased one at most 1.
const std::string kGlassSphere = R"(<shape type="sphere"><point name="center" x="0" y="2" z="0"/>
  <float name="radius" value="1"/><bsdf type="dielectric"><float name="intIOR" value="1.5"/></bsdf></shape>)";

TEST(SmsCounting, TwoRefractionsThroughAGlassSphere) {
    auto scene = load(sceneXml(kGlassSphere, Vec3(0.3, 5, 0.2)));
    for (const Vec3 &from : {Vec3(0.2, 0.5, 0.1), Vec3(-0.4, 0.5, 0.3)}) {
        const Intersection x1 = receiverAt(*scene, from);
        EXPECT_EQ(distinctSolutions(*scene, x1, Vec3(0.3, 5, 0.2), 2), 1);
        for (SmsConstraint form : {SmsConstraint::AngleDifference, SmsConstraint::HalfVector}) {
            SmsSettings unbiased;
            unbiased.constraint = form;
            const Counted u = countSolutions(*scene, x1, Vec3(0.3, 5, 0.2), unbiased, 2000, 2);
            std::printf("glass sphere, %s: unbiased mean %.4f +- %.4f\n",
                        form == SmsConstraint::AngleDifference ? "angle" : "halfvector", u.estimate.mean,
                        u.estimate.stderr_);
            EXPECT_GT(u.estimate.stderr_, 0.0);
            EXPECT_NEAR(u.estimate.mean, 1.0, 4.5 * u.estimate.stderr_);
            SmsSettings biased = unbiased;
            biased.biased = true;
            biased.trials = 4;
            EXPECT_LE(countSolutions(*scene, x1, Vec3(0.3, 5, 0.2), biased, 200, 2).maxValue, 1.0);
        }
    }
}

// The solid angle at x_1 per unit area at x_3 through a refracting plane, against finite differences of the
// solved directions as x_3 moves in its tangent plane (a traced bundle, §6.3), and through a plane mirror against
// the image method's |cos_3| / (d_1 + d_2)^2.
TEST(SmsGeometry, MatchesTracedBundleAndImageMethod) {
    SmsSettings tight;
    tight.solverThreshold = 1e-13;
    tight.maxIterations = 60;
    {
        auto scene = load(sceneXml(kGlassPlane, Vec3(0, 1, 0), -1));
        const Intersection x1 = receiverAt(*scene, Vec3(0.7, -0.5, 0.2));
        const Vec3 x3(0.1, 1.3, -0.2), n3 = normalize(Vec3(0.2, -1, 0.3));
        ManifoldVertex e;
        e.p = x3;
        e.ng = e.n = n3;
        coordinateSystem(n3, e.dpdu, e.dpdv);
        const auto direction = [&](const Vec3 &target) {
            for (uint64_t k = 0;; ++k) {
                IndependentSampler sampler(1, k, 0);
                const auto x2 = solveSpecularVertex(*scene, x1, target, casterOf(*scene), tight, sampler);
                if (x2) return normalize(x2->p - x1.p);
            }
        };
        IndependentSampler sampler(1, 0, 0);
        std::optional<Intersection> x2;
        for (uint64_t k = 0; !x2; ++k) {
            IndependentSampler s(2, k, 0);
            x2 = solveSpecularVertex(*scene, x1, x3, casterOf(*scene), tight, s);
        }
        const std::optional<double> g = specularChainGeometry(x1, {*x2}, e);
        ASSERT_TRUE(g);
        const double h = 1e-4;
        const Vec3 du = (direction(x3 + e.dpdu * h) - direction(x3 - e.dpdu * h)) / (2 * h);
        const Vec3 dv = (direction(x3 + e.dpdv * h) - direction(x3 - e.dpdv * h)) / (2 * h);
        const double traced = cross(du, dv).length();
        EXPECT_NEAR(*g, traced, 1e-4 * traced);
    }
    {
        auto scene = load(sceneXml(kPlaneMirror, Vec3(1, 1, 0)));
        const Intersection x1 = receiverAt(*scene, Vec3(0, 1, 0));
        const Vec3 x3(1, 1.2, 0.3), n3 = normalize(Vec3(1, -0.5, 0.2));
        ManifoldVertex e;
        e.p = x3;
        e.ng = e.n = n3;
        coordinateSystem(n3, e.dpdu, e.dpdv);
        std::optional<Intersection> x2;
        for (uint64_t k = 0; !x2; ++k) {
            IndependentSampler s(2, k, 0);
            x2 = solveSpecularVertex(*scene, x1, x3, casterOf(*scene), tight, s);
        }
        const Vec3 image(4 - x3.x, x3.y, x3.z);  // x3 mirrored in x = 2
        const Vec3 d = normalize(x2->p - x3);
        const double expected = std::abs(dot(n3, d)) / (image - x1.p).lengthSquared();
        const std::optional<double> g = specularChainGeometry(x1, {*x2}, e);
        ASSERT_TRUE(g);
        EXPECT_NEAR(*g, expected, 1e-9 * expected);
    }
}

// The radiance SmsConnection estimates at a diffuse receiver (albedo 0.5) under a point light (I = 10) against
// the closed forms of SMS_PORTAL_NOTES.md §1.6: ρ/π E with E from the image method for the plane mirror and from
// the flat-interface formula E(r) = I T(θi) sin θi / (r (h / cos²θi + d cos θi / (η cos³θt))).
MeanCI estimateAt(const Scene &scene, const Intersection &x1, const Properties &props, int n, int budget = 1) {
    const SmsConnection sms(props);
    sms.check(scene);
    sms.begin();
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
        IndependentSampler sampler(17, static_cast<uint64_t>(i), 0);
        const double v = sms.estimate(scene, sampler, x1, budget).r;
        sum += v;
        sum2 += v * v;
    }
    MeanCI r;
    r.mean = sum / n;
    r.stderr_ = std::sqrt(std::max(0.0, sum2 / n - r.mean * r.mean) / (n - 1));
    EXPECT_EQ(sms.statistics().guardHits.load(), 0u);
    return r;
}

TEST(SmsClosedForm, PlaneMirrorImageMethod) {
    auto scene = load(sceneXml(kPlaneMirror, Vec3(1, 1, 0)));
    const Intersection x1 = receiverAt(*scene, Vec3(0, 1, 0));
    // Image of the light (1, 1, 0) in x = 2: (3, 1, 0); x_1 = 0: cos θ = 1/√10, distance² = 10.
    const double expected = 0.5 / kPi * 10 * (1 / std::sqrt(10.0)) / 10;
    for (const std::string constraint : {"angle", "halfvector"}) {
        Properties props(ObjectKind::Integrator, "sms", {});
        props.set("constraint", Properties::Type::String, constraint, {});
        const MeanCI e = estimateAt(*scene, x1, props, 2000);
        EXPECT_NEAR(e.mean, expected, 4.5 * e.stderr_ + 1e-9 * expected) << constraint;
    }
}

TEST(SmsClosedForm, FlatRefractingInterface) {
    const double h = 1, d = 1, eta = 1.5;
    auto scene = load(sceneXml(kGlassPlane, Vec3(0, h, 0), -d));
    for (double r : {0.3, 0.8, 1.6}) {
        const Intersection x1 = receiverAt(*scene, Vec3(r, -0.5, 0));
        // Solve r = h tan θi + d tan θt for θi by bisection.
        double lo = 0, hi = kPi / 2 - 1e-9;
        for (int i = 0; i < 200; ++i) {
            const double mid = 0.5 * (lo + hi);
            const double thetaT = std::asin(std::sin(mid) / eta);
            (h * std::tan(mid) + d * std::tan(thetaT) < r ? lo : hi) = mid;
        }
        const double thetaI = 0.5 * (lo + hi), thetaT = std::asin(std::sin(thetaI) / eta);
        const double T = 1 - fresnelDielectric(std::cos(thetaI), eta);
        const double E =
            10 * T * std::sin(thetaI) /
            (r * (h / std::pow(std::cos(thetaI), 2) + d * std::cos(thetaI) / (eta * std::pow(std::cos(thetaT), 3))));
        for (const std::string constraint : {"angle", "halfvector"}) {
            Properties props(ObjectKind::Integrator, "sms", {});
            props.set("constraint", Properties::Type::String, constraint, {});
            const MeanCI e = estimateAt(*scene, x1, props, 2000);
            EXPECT_NEAR(e.mean, 0.5 / kPi * E, 4.5 * e.stderr_ + 1e-6 * E) << constraint << " r = " << r;
        }
    }
}

// A glass slab (two parallel refracting planes y = 0 and y = -t, index η) over a diffuse floor at depth d under
// it and a point light at height h above it. The flat-interface formula of SMS_PORTAL_NOTES.md §1.6 extends to
// the slab the same way it is derived: E = I T_in T_out sin θi dθi / (r dr) with the lateral offset
// r(θi) = (h + d) tan θi + t tan θt, so dr/dθi = (h + d) / cos²θi + t cos θi / (η cos³θt) (sin θt = sin θi / η).
// Only two-vertex chains reach the floor (the one-vertex chain through the lower plane is blocked by the upper).
TEST(SmsClosedForm, GlassSlabTwoRefractions) {
    const double h = 1, t = 0.5, d = 1, eta = 1.5;
    const std::string lower = R"(<shape type="rectangle"><bsdf type="dielectric"><float name="intIOR" value="1.5"/>
      <float name="extIOR" value="1"/></bsdf><transform name="toWorld"><scale x="3" y="3" z="3"/>
      <rotate x="1" angle="90"/><translate y="-0.5"/></transform></shape>)";
    auto scene = load(sceneXml(kGlassPlane + lower, Vec3(0, h, 0), -t - d));
    for (double r : {0.3, 1.1}) {
        const Intersection x1 = receiverAt(*scene, Vec3(r, -t - 0.5, 0));
        double lo = 0, hi = kPi / 2 - 1e-9;
        for (int i = 0; i < 200; ++i) {
            const double mid = 0.5 * (lo + hi);
            const double thetaT = std::asin(std::sin(mid) / eta);
            ((h + d) * std::tan(mid) + t * std::tan(thetaT) < r ? lo : hi) = mid;
        }
        const double thetaI = 0.5 * (lo + hi), thetaT = std::asin(std::sin(thetaI) / eta);
        const double T =
            (1 - fresnelDielectric(std::cos(thetaI), eta)) * (1 - fresnelDielectric(std::cos(thetaT), 1 / eta));
        const double E = 10 * T * std::sin(thetaI) /
                         (r * ((h + d) / std::pow(std::cos(thetaI), 2) +
                               t * std::cos(thetaI) / (eta * std::pow(std::cos(thetaT), 3))));
        for (const std::string constraint : {"angle", "halfvector"}) {
            Properties props(ObjectKind::Integrator, "sms", {});
            props.set("constraint", Properties::Type::String, constraint, {});
            props.set("bounces", Properties::Type::Integer, int64_t(2), {});
            const MeanCI e = estimateAt(*scene, x1, props, 10000, 2);
            std::printf("slab r = %.1f, %s: %.6f +- %.6f, closed form %.6f\n", r, constraint.c_str(), e.mean, e.stderr_,
                        0.5 / kPi * E);
            EXPECT_NEAR(e.mean, 0.5 / kPi * E, 4.5 * e.stderr_ + 1e-6 * E) << constraint << " r = " << r;
            // With a budget of one vertex (the depth limit) the slab's caustic is not sms's.
            EXPECT_EQ(estimateAt(*scene, x1, props, 20, 1).mean, 0.0);
        }
    }
}

TEST(SmsParameters, RejectsBadValues) {
    const auto fails = [](const std::string &name, auto value) {
        Properties p(ObjectKind::Integrator, "sms", {});
        if constexpr (std::is_same_v<decltype(value), const char *>)
            p.set(name, Properties::Type::String, std::string(value), {});
        else
            p.set(name, Properties::Type::Integer, int64_t(value), {});
        EXPECT_THROW(SmsConnection{p}, SceneError) << name;
    };
    fails("trials", 0);
    fails("maxIterations", 0);
    fails("bounces", 3);
    fails("bounces", 0);
    fails("constraint", "spherical");
}

// --- The `sms` integrator against `path` (block means of independent seeds, support/agreement.h). The lights
// of the caustic scenes are enlarged so that the path tracer converges in test time. The sphere scene gets a
// second light that sms does not connect to, so that the partition is tested with partial flags (more scenes,
// and the mirror sphere flagged out of the casters, in test_long_sms.cpp).

std::unique_ptr<Integrator> integrator(const Scene &scene, const std::string &type, int64_t bounces = 1) {
    Properties props(ObjectKind::Integrator, type, {});
    props.set("maxDepth", Properties::Type::Integer, scene.integratorProperties().getInt("maxDepth", -1), {});
    if (bounces > 1) props.set("bounces", Properties::Type::Integer, bounces, {});
    return createIntegrator(type, props, true);
}

struct RenderCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const RenderCase &c, std::ostream *os) { *os << c.name; }
    std::string name, scene;
    std::vector<Edit> edits;
    int resolution, pathSpp, smsSpp;
    int64_t bounces = 1;
};

class SmsAgreement : public ::testing::TestWithParam<RenderCase> {};

TEST_P(SmsAgreement, UnbiasedSmsAgreesWithThePathTracer) {
    const RenderCase &c = GetParam();
    auto scene = loadSharedScene(c.scene, c.resolution, c.edits);
    const BlockStats path = blockStats(*scene, *integrator(*scene, "path"), 8, 32, c.pathSpp);
    expectAgreement(path, blockStats(*scene, *integrator(*scene, "sms", c.bounces), 8, 32, c.smsSpp), c.name);
}

const Edit kBigSphereLight{R"(<scale x="0.15" y="0.15" z="0.15"/>)", R"(<scale x="0.6" y="0.6" z="0.6"/>)"};
const Edit kBigSphereLightRadiance{R"(<spectrum name="radiance" value="3000"/>)",
                                   R"(<spectrum name="radiance" value="190"/>)"};
// A second light that sms does not connect to (causticEmitter = false): its caustics stay with the path tracer.
const Edit kSecondLight{R"(<shape type="sphere">)", R"(<shape type="rectangle"><transform name="toWorld">
    <scale value="0.5"/><rotate x="1" angle="90"/><translate x="-2" y="4" z="1"/></transform>
    <emitter type="area"><spectrum name="radiance" value="40"/><boolean name="causticEmitter" value="false"/>
    </emitter></shape><shape type="sphere">)"};
INSTANTIATE_TEST_SUITE_P(Scenes, SmsAgreement,
                         ::testing::Values(RenderCase{"sphere_partial_flags",
                                                      "sphere-caustic",
                                                      {kBigSphereLight, kBigSphereLightRadiance, kSecondLight},
                                                      16,
                                                      128,
                                                      32},
                                           // Two-refraction chains through the glass sphere are sms's too (path
                                           // needs more samples for the rare paths of that caustic, as in
                                           // test_long_sms.cpp).
                                           RenderCase{"sphere_two_bounces",
                                                      "sphere-caustic",
                                                      {kBigSphereLight, kBigSphereLightRadiance, kSecondLight},
                                                      16,
                                                      512,
                                                      64,
                                                      2},
                                           RenderCase{"pool",
                                                      "pool-caustic",
                                                      {{R"(<scale x="0.1" y="0.1" z="0.1"/>)",
                                                        R"(<scale x="0.4" y="0.4" z="0.4"/>)"},
                                                       {R"(value="1600")", R"(value="100")"}},
                                                      16,
                                                      128,
                                                      32}),
                         [](const auto &info) { return info.param.name; });

// Same seed, same bits with one and two threads; another seed, other bits.
TEST(SmsRender, SameBitsForAnyThreadCount) {
    auto scene = loadSharedScene("sphere-caustic", 24);
    const auto sms = integrator(*scene, "sms");
    const auto render = [&](uint64_t seed, int threads) {
        RenderOptions opt;
        opt.spp = 2;
        opt.seed = seed;
        opt.threads = threads;
        RenderStats stats;
        return sms->render(*scene, opt, stats);
    };
    const Bitmap a = render(7, 1), b = render(7, 2), c = render(8, 2);
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(a.rgb, b.rgb);
    EXPECT_NE(a.rgb, c.rgb);
}

// A time budget renders whole passes, like `path`.
TEST(SmsRender, TimeBudget) {
    auto scene = loadSharedScene("pool-caustic", 16);
    RenderOptions opt;
    opt.timeLimit = 0.5;
    RenderStats stats;
    const Bitmap image = integrator(*scene, "sms")->render(*scene, opt, stats);
    EXPECT_GT(stats.samplesPerPixel, 0);
    EXPECT_GT(regionMean(image, 0, 0, 16, 16).mean, 0.0);
}

// Flags that sms cannot honour are errors that name the file and line.
TEST(SmsRender, RejectsImpossibleFlags) {
    const auto fails = [](const std::string &xml, const std::string &needle) {
        auto scene = load(xml);
        RenderOptions opt;
        opt.spp = 1;
        RenderStats stats;
        try {
            integrator(*scene, "sms")->render(*scene, opt, stats);
            ADD_FAILURE() << "no error for " << needle;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find(".xml:"), std::string::npos) << e.what();
        }
    };
    fails(sceneXml(R"(<shape type="sphere"><boolean name="causticCaster" value="true"/></shape>)", Vec3(0, 3, 0)),
          "causticCaster");
    fails(
        sceneXml(R"(<emitter type="constant"><boolean name="causticEmitter" value="true"/></emitter>)", Vec3(0, 3, 0)),
        "causticEmitter");
}

}  // namespace
}  // namespace pf::test
