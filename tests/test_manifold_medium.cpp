// Medium vertices in specular chains (ALGORITHMS.md §6.7, [TR §7], [TH ch. 7]) on the analytic set-up of a point
// light above a glass sphere (eta = 1.5, tests/scenes/manifold/glass_sphere.xml) filled with a medium: the light
// refracts into the sphere, scatters at one to three medium vertices inside it, refracts out and reaches the
// floor. The medium's coefficients do not enter the chain's geometry, so the scene needs no medium element. Checks:
// the medium constraint c = T(ω_in)^T ω_out and the rows of ∇C it contributes (and those a medium neighbour adds
// to a surface constraint) against central finite differences; propagation with the chain's own direction
// reproduces the chain; walks converge onto paths that keep every offset and segment length, and walk back; the
// generalized geometry term through medium vertices (the dense system with the length rows) against the traced
// finite-difference solid-angle/area ratio. The walk and propagation checks run a second time with an
// index-matched boundary (the null BSDF) across the sphere (glass_sphere_index_matched.xml), which chain
// segments cross without bending: walks and propagation must pass straight through it (manifold_walk.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bsdf/bsdf.h"
#include "core/frame.h"
#include "core/rng.h"
#include "manifold/dense_system.h"
#include "manifold/generalized_geometry.h"
#include "manifold/manifold_walk.h"
#include "manifold/offset_jacobian.h"
#include "manifold/specular_constraint.h"
#include "scene/scene.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

double uniform(PCG32 &rng, double lo, double hi) { return lo + (hi - lo) * rng.nextDouble(); }

Vec3 randomUnit(PCG32 &rng) {
    for (;;) {
        const Vec3 v(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
        if (v.lengthSquared() > 0.01 && v.lengthSquared() < 1) return normalize(v);
    }
}

const std::string kSphere = "glass_sphere.xml", kIndexMatched = "glass_sphere_index_matched.xml";

std::unique_ptr<Scene> glassSphere(const std::string &file = kSphere) {
    return loadScene(std::string(PATHFARM_SOURCE_DIR) + "/tests/scenes/manifold/" + file);
}

// The index-matched surfaces that the segments of a chain cross.
int crossings(const Scene &scene, const std::vector<ManifoldVertex> &chain) {
    int count = 0;
    for (size_t i = 0; i + 1 < chain.size(); ++i) {
        Ray ray = scene.spawnRayTo(chain[i].p, chain[i + 1].p);
        Intersection its;
        while (scene.intersect(ray, its) && its.bsdf()->isNull()) {
            ++count;
            ray.tmin = its.t + scene.epsilonAt(its.p);
        }
    }
    return count;
}

// A vertex with a flat chart around a random normal at p (a neighbour whose own constraint is not evaluated).
ManifoldVertex chartVertex(const Vec3 &p, PCG32 &rng) {
    ManifoldVertex v;
    v.p = p;
    v.ng = v.n = randomUnit(rng);
    coordinateSystem(v.n, v.dpdu, v.dpdv);
    return v;
}

// Central differences of constraintValue(prev, v, next) when vertex `which` (-1, 0, 1) moves along e.
Vec2 numericColumn(ManifoldVertex prev, ManifoldVertex v, ManifoldVertex next, int which, const Vec3 &e) {
    constexpr double h = 1e-6;
    ManifoldVertex &q = which < 0 ? prev : which > 0 ? next : v;
    const Vec3 p = q.p;
    q.p = p + e * h;
    const Vec2 plus = *constraintValue(prev, v, next);
    q.p = p - e * h;
    const Vec2 minus = *constraintValue(prev, v, next);
    return (plus - minus) * (1 / (2 * h));
}

void expectColumn(const Vec2 &analytic, const Vec2 &numeric) {
    EXPECT_NEAR(analytic.x, numeric.x, 1e-6 * (1 + std::abs(numeric.x)));
    EXPECT_NEAR(analytic.y, numeric.y, 1e-6 * (1 + std::abs(numeric.y)));
}

// Every column of v's row of ∇C (both chart directions of each neighbour and the axis of medium ones) against
// finite differences.
void checkRow(const ManifoldVertex &prev, const ManifoldVertex &v, const ManifoldVertex &next) {
    const std::optional<ConstraintDerivatives> d = constraintDerivatives(prev, v, next);
    ASSERT_TRUE(d);
    const ManifoldVertex *vertices[3] = {&prev, &v, &next};
    const Mat2 *blocks[3] = {&d->prev, &d->self, &d->next};
    const Vec2 *axes[3] = {&d->prevAxis, &d->selfAxis, &d->nextAxis};
    for (int which = -1; which <= 1; ++which) {
        const ManifoldVertex &q = *vertices[which + 1];
        const Mat2 &b = *blocks[which + 1];
        if (which == 0 && v.type != ManifoldVertexType::Medium) continue;  // a surface's own chart: other tests
        expectColumn(Vec2(b(0, 0), b(1, 0)), numericColumn(prev, v, next, which, q.dpdu));
        expectColumn(Vec2(b(0, 1), b(1, 1)), numericColumn(prev, v, next, which, q.dpdv));
        if (q.type == ManifoldVertexType::Medium)
            expectColumn(*axes[which + 1], numericColumn(prev, v, next, which, q.n));
        else
            EXPECT_TRUE(axes[which + 1]->x == 0 && axes[which + 1]->y == 0);
    }
}

TEST(ManifoldMedium, MediumConstraintIsTheScatteringDirectionInTheIncomingFrame) {
    PCG32 rng(3, 1);
    for (int trial = 0; trial < 50; ++trial) {
        const Vec3 prev = randomUnit(rng) * 2.0, p = randomUnit(rng) * 0.5, next = randomUnit(rng) * 3.0;
        const std::optional<ManifoldVertex> v = ManifoldVertex::medium(p, prev, next);
        ASSERT_TRUE(v);
        const Vec3 wIn = normalize(p - prev), wOut = normalize(next - p);
        EXPECT_NEAR(v->segment, (p - prev).length(), 1e-12);
        EXPECT_NEAR(dot(v->dpdu, wIn), 0.0, 1e-12);
        EXPECT_NEAR(dot(v->dpdv, wIn), 0.0, 1e-12);
        EXPECT_NEAR(dot(v->dpdu, v->dpdv), 0.0, 1e-12);
        // o and the forward/backward sign recover ω_out in the incoming frame.
        EXPECT_NEAR((*microfacetNormal(*v) - wOut).length(), 0.0, 1e-12);
        EXPECT_EQ(v->halfVectorAbove, dot(wIn, wOut) > 0);
    }
}

TEST(ManifoldMedium, ConstraintRowsMatchFiniteDifferences) {
    PCG32 rng(5, 2);
    for (int trial = 0; trial < 50; ++trial) {
        const Vec3 pPrev = randomUnit(rng) * 2.0, p = randomUnit(rng) * 0.5, pNext = randomUnit(rng) * 3.0;
        const ManifoldVertex v = *ManifoldVertex::medium(p, pPrev, pNext);
        // Surface neighbours, then medium neighbours (their own neighbours are arbitrary points).
        checkRow(chartVertex(pPrev, rng), v, chartVertex(pNext, rng));
        const ManifoldVertex mPrev = *ManifoldVertex::medium(pPrev, randomUnit(rng) * 4.0, p);
        const ManifoldVertex mNext = *ManifoldVertex::medium(pNext, p, randomUnit(rng) * 4.0);
        checkRow(mPrev, v, mNext);
    }
}

TEST(ManifoldMedium, SurfaceRowsAlongMediumNeighboursMatchFiniteDifferences) {
    const auto scene = glassSphere();
    PCG32 rng(7, 3);
    for (int trial = 0; trial < 30; ++trial) {
        // A refraction at the sphere between a medium vertex inside and one outside it.
        const Vec3 outside = Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 3);
        Intersection its;
        ASSERT_TRUE(scene->intersect(Ray(outside, normalize(Vec3(0, 0, 0.3) - outside)), its));
        const Vec3 inside = its.p * 0.3 + Vec3(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), 0);
        const ManifoldVertex s = *ManifoldVertex::constrained(its, outside, inside, true);
        checkRow(*ManifoldVertex::medium(outside, Vec3(0, 0, 5), its.p), s,
                 *ManifoldVertex::medium(inside, its.p, Vec3(0, 0, -3)));
    }
}

// Refraction of a travel direction d into (or out of) the glass sphere at its outward normal n: the
// library's scatterAbout (tested by test_manifold_walk), with eta = eta_o / eta_i.
std::optional<Vec3> refract(const Vec3 &d, const Vec3 &n) {
    const std::optional<Vec3> wo = scatterAbout(-d, n, Scattering::Refraction, dot(d, n) < 0 ? 1.5 : 1 / 1.5);
    return wo ? std::optional<Vec3>(normalize(*wo)) : std::nullopt;
}

// A path from the point light x1 along d: into the sphere, `media` medium vertices inside it (each scattering by
// up to 20 degrees), out of it and onto the floor, as a chain. Empty when the trace fails (a miss, total
// internal reflection).
std::vector<ManifoldVertex> mediumChain(const Scene &scene, const Vec3 &x1, const Vec3 &d, int media, PCG32 &rng) {
    Intersection entry, exit, floor;
    const auto intersect = [&](const Vec3 &o, const Vec3 &dir, Intersection &its) {
        return intersectOpaque(scene, Ray(o, dir, scene.epsilonAt(o)), its);
    };
    if (!intersect(x1, d, entry)) return {};
    std::optional<Vec3> dir = refract(d, entry.n);
    if (!dir) return {};
    std::vector<Vec3> points = {x1, entry.p};
    for (int m = 0; m < media; ++m) {
        const Vec3 &from = points.back();
        if (!intersect(from, *dir, exit)) return {};
        points.push_back(from + *dir * ((exit.p - from).length() * uniform(rng, 0.2, 0.6)));
        const Frame f(*dir);
        const double theta = uniform(rng, 0, 20) * kPi / 180, phi = uniform(rng, 0, 2 * kPi);
        dir = f.toWorld(Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    }
    if (!intersect(points.back(), *dir, exit)) return {};
    dir = refract(*dir, exit.n);
    if (!dir || !intersect(exit.p, *dir, floor)) return {};
    if (exit.shape != entry.shape || floor.shape == entry.shape) return {};
    points.push_back(exit.p);
    points.push_back(floor.p);
    std::vector<ManifoldVertex> chain = {ManifoldVertex::fixedPosition(x1)};
    const size_t n = points.size();
    for (size_t i = 1; i + 1 < n; ++i) {
        const Intersection &its = i == 1 ? entry : exit;
        const auto v = i == 1 || i == n - 2 ? ManifoldVertex::constrained(its, points[i - 1], points[i + 1], true)
                                            : ManifoldVertex::medium(points[i], points[i - 1], points[i + 1]);
        if (!v) return {};
        chain.push_back(*v);
    }
    chain.push_back(*ManifoldVertex::surface(floor));
    return chain;
}

// A random chain through 1-3 medium vertices from a light 4 above the sphere.
std::vector<ManifoldVertex> randomChain(const Scene &scene, PCG32 &rng, Vec3 &x1, Vec3 &d) {
    for (;;) {
        x1 = Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 4);
        d = normalize(Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 0) - x1);
        const std::vector<ManifoldVertex> chain =
            mediumChain(scene, x1, d, 1 + static_cast<int>(rng.nextUInt() % 3), rng);
        if (!chain.empty()) return chain;
    }
}

// Whether the walked chain keeps every constraint: refractions ideal, medium offsets and segments as in `old`.
void expectOnManifold(const std::vector<ManifoldVertex> &chain, const std::vector<ManifoldVertex> &old) {
    for (size_t i = 1; i + 1 < chain.size(); ++i) {
        const Vec2 c = *constraintValue(chain[i - 1], chain[i], chain[i + 1]) - old[i].offset;
        EXPECT_LT(std::hypot(c.x, c.y), 1e-8) << "vertex " << i;
        if (old[i].type == ManifoldVertexType::Medium) {
            EXPECT_NEAR((chain[i].p - chain[i - 1].p).length(), old[i].segment, 1e-9);
        }
    }
}

// The walk and propagation checks on the sphere, and with the index-matched boundary across it, where they count
// the chains that cross it (at least 10 must).
class ManifoldMediumScenes : public ::testing::TestWithParam<std::string> {
protected:
    void expectCrossings(int crossing) const {
        if (GetParam() == kIndexMatched) {
            EXPECT_GE(crossing, 10) << "too few chains cross the boundary";
        }
    }
};

// Walks from random chains to targets near their ends converge and walk back.
TEST_P(ManifoldMediumScenes, WalksThroughMediumVerticesConvergeAndReturn) {
    const std::string &file = GetParam();
    const auto scene = glassSphere(file);
    ManifoldWalkParameters params;
    params.epsilon = 1e-12;
    const ManifoldWalk walker(*scene, params);
    PCG32 rng(11, 5);
    int converged = 0, iterations = 0, crossing = 0;
    constexpr int kTrials = 40;
    for (int trial = 0; trial < kTrials; ++trial) {
        Vec3 x1, d;
        const std::vector<ManifoldVertex> chain = randomChain(*scene, rng, x1, d);
        const bool crosses = crossings(*scene, chain) > 0;
        const Vec3 end = chain.back().p;
        Intersection its;
        ASSERT_TRUE(scene->intersect(
            Ray(Vec3(end.x + uniform(rng, -0.03, 0.03), end.y + uniform(rng, -0.03, 0.03), -2.5), Vec3(0, 0, -1)),
            its));
        const WalkResult result = walker.walk(chain, *ManifoldVertex::surface(its));
        if (!result.converged()) continue;
        ++converged;
        crossing += crosses;
        iterations += result.stats.iterations;
        EXPECT_LT((result.chain.back().p - its.p).length(), 1e-12);
        expectOnManifold(result.chain, chain);
        // And back to where it started.
        const WalkResult back = walker.walk(result.chain, chain.back());
        ASSERT_TRUE(back.converged());
        for (size_t i = 1; i + 1 < chain.size(); ++i)
            EXPECT_LT((back.chain[i].p - chain[i].p).length(), 1e-6) << "vertex " << i;
    }
    std::printf("%s walks: %d of %d converged (%d across an index-matched boundary), %d iterations\n", file.c_str(),
                converged, kTrials, crossing, iterations);
    // Small steps away from folds: nearly all converge, in few (quadratically convergent) iterations: about 3.2
    // per walk (without the length rows' coupling to the predecessor, 5.6).
    EXPECT_GE(converged, kTrials * 9 / 10);
    EXPECT_LE(iterations, converged * 4);
    expectCrossings(crossing);
}

// Propagation with the chain's own direction reproduces the chain; with directions about it, the floor area per
// unit solid angle at the point light (offsets and segments held) is 1 / G through the medium vertices. A crossing
// bends no ray: G is the same with the boundary, and propagation passes through it.
TEST_P(ManifoldMediumScenes, PropagationReproducesTheChainAndItsGeometryTerm) {
    const std::string &file = GetParam();
    const auto scene = glassSphere(file);
    const ManifoldWalk walker(*scene);
    PCG32 rng(13, 6);
    int crossing = 0;
    for (int trial = 0; trial < 30; ++trial) {
        Vec3 x1, d;
        const std::vector<ManifoldVertex> chain = randomChain(*scene, rng, x1, d);
        crossing += crossings(*scene, chain) > 0;
        const auto traced = walker.propagate(chain, x1, d, nullptr);
        ASSERT_TRUE(traced);
        ASSERT_EQ(traced->size(), chain.size());
        for (size_t i = 0; i < chain.size(); ++i) EXPECT_LT(((*traced)[i].p - chain[i].p).length(), 1e-6);
        expectOnManifold(*traced, chain);

        const std::optional<double> g = generalizedGeometry(chain);
        ASSERT_TRUE(g);
        const Frame f(d);
        constexpr double h = 1e-6;
        const auto landing = [&](double s, double t) {
            const auto moved = walker.propagate(chain, x1, normalize(d + f.s * s + f.t * t), nullptr);
            EXPECT_TRUE(moved);
            return moved ? moved->back().p : Vec3(0.0);
        };
        const Vec3 ds = (landing(h, 0) - landing(-h, 0)) / (2 * h), dt = (landing(0, h) - landing(0, -h)) / (2 * h);
        // A point has no cosine: G is the solid angle at x_1 per unit area at the floor.
        EXPECT_NEAR(*g * cross(ds, dt).length(), 1.0, 1e-4) << "trial " << trial;
    }
    std::printf("%s: %d of 30 chains cross an index-matched boundary\n", file.c_str(), crossing);
    expectCrossings(crossing);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ManifoldMediumScenes, ::testing::Values(kSphere, kIndexMatched),
                         [](const auto &info) { return info.param == kSphere ? "Sphere" : "IndexMatched"; });

// The offset Jacobian with medium vertices (offset_jacobian.h): on a chain x_a, M_1, M_2, x_b, M_3, x_c (x_a, x_c
// fixed points, x_b on the floor, the medium vertices walked from x_a before x_b and from x_c after it), the
// factor |∂[x_b, M_1, M_2, M_3] / ∂[x_b, (o, ℓ)_1, (o, ℓ)_2, (o, ℓ)_3]| against 1 / |det| of the finite-difference
// Jacobian of the map from positions (x_b's chart, each M's three world axes) to those coordinates.
TEST(ManifoldMedium, OffsetJacobianMatchesFiniteDifferences) {
    const auto scene = glassSphere();
    PCG32 rng(17, 7);
    for (int trial = 0; trial < 20; ++trial) {
        Intersection floor;
        ASSERT_TRUE(scene->intersect(Ray(Vec3(uniform(rng, 2, 3), uniform(rng, 2, 3), -2.5), Vec3(0, 0, -1)), floor));
        const Vec3 a(uniform(rng, 1, 2), uniform(rng, 1, 2), 1), c(uniform(rng, 3, 4), uniform(rng, 3, 4), -1);
        const Vec3 m1 = a + Vec3(uniform(rng, 0, 1), uniform(rng, 0, 1), -0.8);
        const Vec3 m2 = m1 + Vec3(uniform(rng, 0, 1), uniform(rng, 0, 1), -0.8);
        const Vec3 m3 = c + Vec3(uniform(rng, -1, 0), uniform(rng, -1, 0), -0.8);
        const std::vector<ManifoldVertex> chain = {
            ManifoldVertex::fixedPosition(a),         *ManifoldVertex::medium(m1, a, m2),
            *ManifoldVertex::medium(m2, m1, floor.p), *ManifoldVertex::surface(floor),
            *ManifoldVertex::medium(m3, floor.p, c),  ManifoldVertex::fixedPosition(c)};
        const std::optional<double> j = offsetJacobian(chain, 3, {1, 2, 4});
        ASSERT_TRUE(j);

        const ManifoldVertex &b = chain[3];
        const auto coordinates = [&](const std::vector<Vec3> &p) {
            const auto medium = [](const Vec3 &q) {
                ManifoldVertex v = ManifoldVertex::fixedPosition(q);
                v.type = ManifoldVertexType::Medium;
                return v;
            };
            const auto point = [](const Vec3 &q) { return ManifoldVertex::fixedPosition(q); };
            const Vec2 c1 = *constraintValue(point(a), medium(p[0]), point(p[1]));
            const Vec2 c2 = *constraintValue(point(p[0]), medium(p[1]), point(p[2]));
            const Vec2 c3 = *constraintValue(point(c), medium(p[3]), point(p[2]));
            return std::vector<double>{dot(p[2], b.dpdu),
                                       dot(p[2], b.dpdv),
                                       c1.x,
                                       c1.y,
                                       (p[0] - a).length(),
                                       c2.x,
                                       c2.y,
                                       (p[1] - p[0]).length(),
                                       c3.x,
                                       c3.y,
                                       (p[3] - c).length()};
        };
        const std::vector<Vec3> base = {m1, m2, floor.p, m3};
        // The moves: x_b along its chart, each medium vertex along the world axes.
        std::vector<std::pair<size_t, Vec3>> moves = {{2, b.dpdu}, {2, b.dpdv}};
        for (const size_t v : {0u, 1u, 3u})
            for (const Vec3 &e : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}) moves.emplace_back(v, e);
        DenseSystem jacobian(moves.size());
        constexpr double h = 1e-6;
        for (size_t col = 0; col < moves.size(); ++col) {
            std::vector<Vec3> plus = base, minus = base;
            plus[moves[col].first] += moves[col].second * h;
            minus[moves[col].first] -= moves[col].second * h;
            const std::vector<double> fp = coordinates(plus), fm = coordinates(minus);
            for (size_t row = 0; row < moves.size(); ++row) jacobian(row, col) = (fp[row] - fm[row]) / (2 * h);
        }
        EXPECT_NEAR(*j * jacobian.absDeterminant(), 1.0, 1e-5) << "trial " << trial;
    }
}

}  // namespace
}  // namespace pf::test
