// WalkManifold (ALGORITHMS.md §6.4) on analytic configurations loaded through the scene loader
// (tests/scenes/manifold/): reflection off a plane (the mirror-image solution) and off a sphere, refraction through
// a plane (Snell's law solved by bisection) and through a glass sphere (two refractions). Checks: convergence to
// the exact solution with a tight ε, the law of reflection / Snell's law at every found vertex, the reverse walk
// returning to the start, a target across the silhouette failing cleanly, the symmetric virtual plane, offset
// manifolds on the plane and (quadratic convergence) on the sphere, which triangles keep a configuration, and the
// generalized geometry term of a refractor, in both directions (they differ by the étendue factor), against
// finite-difference solid-angle/area ratios obtained by tracing (§6.3). Initial chains and the reference traces use
// the test's own reflection and Snell refraction.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bsdf/bsdf.h"
#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"
#include "manifold/generalized_geometry.h"
#include "manifold/manifold_walk.h"
#include "manifold/specular_constraint.h"
#include "scene/scene.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

std::unique_ptr<Scene> loadManifoldScene(const std::string &name) {
    return loadScene(std::string(PATHFARM_SOURCE_DIR) + "/tests/scenes/manifold/" + name);
}

double uniform(PCG32 &rng, double lo, double hi) { return lo + (hi - lo) * rng.nextDouble(); }

// The test's own optics: mirror reflection and Snell refraction of a travel direction d at geometric normal n
// of a surface with interior/exterior index ratio eta.
std::optional<Vec3> bounce(const Vec3 &d, const Vec3 &n, double eta) {
    if (eta == 1.0) return d - n * (2 * dot(d, n));
    double cosI = -dot(d, n), ratio = 1.0 / eta;
    Vec3 nn = n;
    if (cosI < 0) {
        cosI = -cosI;
        ratio = eta;
        nn = -n;
    }
    const double k = 1 - ratio * ratio * (1 - cosI * cosI);
    if (k < 0) return std::nullopt;
    return normalize(d * ratio + nn * (ratio * cosI - std::sqrt(k)));
}

// Traces from o along d through `specular` delta interactions (mirrors reflect, dielectrics refract) to the next
// surface: the specular hits, then the end hit. A non-zero `tilt` scatters about the normal plus that vector
// instead (a fixed microfacet normal per path, as a glossy surface would sample: an offset manifold, §6.6).
std::optional<std::vector<Intersection>> traceSpecular(const Scene &scene, Vec3 o, Vec3 d, int specular,
                                                       const Vec3 &tilt = Vec3(0.0)) {
    std::vector<Intersection> hits;
    for (int i = 0; i <= specular; ++i) {
        Intersection its;
        if (!scene.intersect(Ray(o, d, scene.epsilonAt(o)), its)) return std::nullopt;
        hits.push_back(its);
        if (i == specular) break;
        if (!its.bsdf()->hasDelta()) return std::nullopt;
        const std::optional<Vec3> next = bounce(d, normalize(its.n + tilt), its.bsdf()->eta());
        if (!next) return std::nullopt;
        o = its.p;
        d = *next;
    }
    return hits;
}

// The chain x_1 (a fixed point) … x_n of a traced path; ideal = false keeps each vertex's current offset.
std::vector<ManifoldVertex> chainFrom(const Vec3 &x1, const std::vector<Intersection> &hits, bool ideal = true) {
    std::vector<ManifoldVertex> chain = {ManifoldVertex::fixedPosition(x1)};
    for (size_t i = 0; i + 1 < hits.size(); ++i) {
        const Vec3 prev = i == 0 ? x1 : hits[i - 1].p;
        chain.push_back(*ManifoldVertex::constrained(hits[i], prev, hits[i + 1].p, ideal));
    }
    chain.push_back(*ManifoldVertex::surface(hits.back()));
    return chain;
}

// The chain of a ray from the point x1 towards `aim` through `specular` interactions (empty if the trace fails).
std::vector<ManifoldVertex> chainTowards(const Scene &scene, const Vec3 &x1, const Vec3 &aim, int specular) {
    const auto hits = traceSpecular(scene, x1, normalize(aim - x1), specular);
    return hits ? chainFrom(x1, *hits) : std::vector<ManifoldVertex>();
}

// The surface point that a ray from `from` along d meets, as a walk target.
ManifoldVertex targetAt(const Scene &scene, const Vec3 &from, const Vec3 &d) {
    Intersection its;
    EXPECT_TRUE(scene.intersect(Ray(from, d), its));
    return *ManifoldVertex::surface(its);
}

// A target on the floor z = -3 of the sphere scenes within ±spread of `end` in x and y.
ManifoldVertex floorTargetNear(const Scene &scene, const Vec3 &end, double spread, PCG32 &rng) {
    const double x = end.x + uniform(rng, -spread, spread), y = end.y + uniform(rng, -spread, spread);
    return targetAt(scene, Vec3(x, y, -2.5), Vec3(0, 0, -1));
}

// Residual of the generalized half-vector condition at vertex i of a chain: |h × n| with h = γ(ω_i + eta ω_o)
// from the vertex's neighbours and n the surface normal; zero exactly for the law of reflection / Snell's law.
double opticsResidual(const std::vector<ManifoldVertex> &chain, size_t i) {
    const ManifoldVertex &v = chain[i];
    const Vec3 wi = normalize(chain[i - 1].p - v.p), wo = normalize(chain[i + 1].p - v.p);
    return cross(normalize(wi + wo * v.eta), v.its.shFrame.n).length();
}

// The chain of a ray from x1 in a random direction within about 30 degrees of straight down, through one
// specular interaction (empty if the trace fails).
std::vector<ManifoldVertex> downwardChain(const Scene &scene, const Vec3 &x1, PCG32 &rng) {
    const Vec3 d = normalize(Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), -1));
    const auto hits = traceSpecular(scene, x1, d, 1);
    return hits ? chainFrom(x1, *hits) : std::vector<ManifoldVertex>();
}

ManifoldWalkParameters tight() {
    ManifoldWalkParameters params;
    params.epsilon = 1e-13;
    return params;
}

// Random walks of single-vertex chains off the plane z = 0: x_1 0.5-1.5 above it, targets on the receiver at
// height receiverZ within ±spread of the traced end. exact(x1, target) is the reference solution.
template <typename Exact>
void checkPlanarWalks(const std::string &sceneName, Scattering scattering, double receiverZ, double spread,
                      const Exact &exact) {
    const auto scene = loadManifoldScene(sceneName);
    const ManifoldWalk walker(*scene, tight());
    PCG32 rng(1, 1);
    const Vec3 towardsReceiver(0, 0, receiverZ > 0 ? 1 : -1);
    for (int trial = 0; trial < 20; ++trial) {
        const Vec3 x1(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.5, 1.5));
        const std::vector<ManifoldVertex> chain = downwardChain(*scene, x1, rng);
        ASSERT_EQ(chain.size(), 3u);
        ASSERT_EQ(chain[1].scattering, scattering);
        ASSERT_NEAR(chain[1].eta, scattering == Scattering::Reflection ? 1.0 : 1.5, 1e-15);
        const Vec3 t = Vec3(chain[2].p.x + uniform(rng, -spread, spread), chain[2].p.y + uniform(rng, -spread, spread),
                            receiverZ) -
                       towardsReceiver * 0.5;
        const ManifoldVertex target = targetAt(*scene, t, towardsReceiver);
        const WalkResult result = walker.walk(chain, target);
        ASSERT_EQ(result.status, WalkStatus::Converged);
        EXPECT_EQ(result.stats.chainSize, 1);
        EXPECT_GE(result.stats.iterations, 1);
        EXPECT_LT((result.chain[1].p - exact(x1, target.p)).length(), 1e-9);
        EXPECT_LT(opticsResidual(result.chain, 1), 1e-9);
        EXPECT_EQ(result.chain.back().p, target.p);
    }
}

// The mirror image of the target in z = 0, joined to x_1, crosses the mirror at the solution.
TEST(ManifoldWalk, PlaneMirrorReachesTheMirrorImageSolution) {
    checkPlanarWalks("plane_mirror.xml", Scattering::Reflection, 2.0, 2.0, [](const Vec3 &x1, const Vec3 &target) {
        const Vec3 image(target.x, target.y, -target.z);
        return x1 + (image - x1) * (x1.z / (x1.z - image.z));
    });
}

// Snell's law through a plane: the solution lies in the plane of incidence, where bisection on
// sin θ_1 = 1.5 sin θ_2 finds it.
TEST(ManifoldWalk, PlaneRefractorSatisfiesSnellsLaw) {
    checkPlanarWalks("plane_refractor.xml", Scattering::Refraction, -2.0, 1.0, [](const Vec3 &x1, const Vec3 &target) {
        const Vec3 flat(target.x - x1.x, target.y - x1.y, 0);
        const double span = flat.length(), h1 = x1.z, h2 = -target.z;
        double lo = 0, hi = span;
        for (int i = 0; i < 200; ++i) {
            const double r = 0.5 * (lo + hi);
            const double f = r / std::hypot(r, h1) - 1.5 * (span - r) / std::hypot(span - r, h2);
            (f < 0 ? lo : hi) = r;
        }
        return Vec3(x1.x, x1.y, 0) + flat * (0.5 * (lo + hi) / span);
    });
}

// Walks a chain through the unit sphere at the origin to target; when that converges, checks that every specular
// vertex lies on the sphere and obeys its optics, then walks back to the original end, which must recover the
// original vertices (the reversibility of §6.5). Returns whether the forward walk converged.
bool walkThereAndBack(const ManifoldWalk &walker, const std::vector<ManifoldVertex> &chain,
                      const ManifoldVertex &target) {
    const WalkResult forward = walker.walk(chain, target);
    if (!forward.converged()) return false;
    const size_t specular = chain.size() - 2;
    EXPECT_EQ(forward.stats.chainSize, static_cast<int>(specular));
    const WalkResult back = walker.walk(forward.chain, chain.back());
    EXPECT_TRUE(back.converged());
    for (size_t i = 1; i <= specular; ++i) {
        EXPECT_NEAR(forward.chain[i].p.length(), 1.0, 1e-12);
        EXPECT_LT(opticsResidual(forward.chain, i), 1e-9);
        if (back.converged()) {
            EXPECT_LT((back.chain[i].p - chain[i].p).length(), 1e-9);
        }
    }
    return true;
}

// 40 walks in a sphere scene: makeStart(rng) gives the chain's fixed start and the direction traced from it through
// `specular` interactions; chains whose trace reaches the floor move their end by up to ±spread. Small moves stay
// on the same sheet of the manifold, so nearly all walks must succeed, each passing walkThereAndBack's checks.
template <typename MakeStart>
void checkSphereWalks(const std::string &sceneName, int specular, double spread, const MakeStart &makeStart) {
    const auto scene = loadManifoldScene(sceneName);
    const ManifoldWalk walker(*scene, tight());
    PCG32 rng(3, static_cast<uint64_t>(specular));
    int converged = 0, tried = 0;
    for (int trial = 0; trial < 200 && tried < 40; ++trial) {
        const auto [start, d] = makeStart(*scene, rng);
        const auto hits = traceSpecular(*scene, start.p, d, specular);
        if (!hits || hits->back().p.z > -2.9) continue;  // the light left the floor
        ++tried;
        std::vector<ManifoldVertex> chain = chainFrom(start.p, *hits);
        chain[0] = start;
        converged += walkThereAndBack(walker, chain, floorTargetNear(*scene, hits->back().p, spread, rng));
    }
    ASSERT_EQ(tried, 40);
    EXPECT_GE(converged, tried * 9 / 10);
}

// Reflection off a sphere from a floor point to another floor point (Alhazen's problem: no closed form; the law
// of reflection at the found point and the point lying on the sphere certify the solution).
TEST(ManifoldWalk, MirrorSphereConvergesAndTheReverseWalkReturns) {
    checkSphereWalks("mirror_sphere.xml", 1, 0.5, [](const Scene &scene, PCG32 &rng) {
        // x_1 on the floor, aimed at the lower side of the sphere.
        const ManifoldVertex start =
            targetAt(scene, Vec3(uniform(rng, 1.5, 3), uniform(rng, -1, 1), -2.5), Vec3(0, 0, -1));
        const Vec3 aim(uniform(rng, 0.5, 0.9), uniform(rng, -0.2, 0.2), uniform(rng, -0.6, -0.3));
        return std::make_pair(start, normalize(aim - start.p));
    });
}

// Two refractions through a glass sphere (a point light above, the floor below); the walk moves the caustic end.
TEST(ManifoldWalk, GlassSphereConvergesAndTheReverseWalkReturns) {
    checkSphereWalks("glass_sphere.xml", 2, 0.1, [](const Scene &, PCG32 &rng) {
        const Vec3 x1(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 4);
        const Vec3 aim(uniform(rng, -0.6, 0.6), uniform(rng, -0.6, 0.6), 0);
        return std::make_pair(ManifoldVertex::fixedPosition(x1), normalize(aim - x1));
    });
}

// With the default ε = 1e-7 and L = the scene's bounding-box diagonal the walk stops within ε L of the target.
TEST(ManifoldWalk, DefaultToleranceIsRelativeToTheSceneScale) {
    const auto scene = loadManifoldScene("glass_sphere.xml");
    const ManifoldWalk walker(*scene);
    EXPECT_NEAR(walker.sceneScale(), scene->bounds().extents().length(), 0.0);
    const Vec3 x1(0.2, 0.1, 4);
    const auto hits = traceSpecular(*scene, x1, normalize(Vec3(0.1, -0.1, 0) - x1), 2);
    ASSERT_TRUE(hits);
    const std::vector<ManifoldVertex> chain = chainFrom(x1, *hits);
    // Entering the glass from outside and leaving it: eta_o / eta_i of §6.1 on both sides.
    ASSERT_EQ(chain[1].scattering, Scattering::Refraction);
    EXPECT_NEAR(chain[1].eta, 1.5, 1e-15);
    EXPECT_NEAR(chain[2].eta, 1 / 1.5, 1e-15);
    const Vec3 end = hits->back().p;
    const ManifoldVertex target = targetAt(*scene, Vec3(end.x + 0.05, end.y - 0.03, -2.5), Vec3(0, 0, -1));
    const WalkResult result = walker.walk(chain, target);
    ASSERT_TRUE(result.converged());
    // The traced end before the target replaced it: x_{n-1} must send its ray within ε L of the target.
    const Vec3 wo = normalize(result.chain[3].p - result.chain[2].p);
    const Vec3 toTarget = target.p - result.chain[2].p;
    EXPECT_LT(cross(wo, toTarget).length(), 1e-7 * walker.sceneScale());
    EXPECT_LE(result.stats.iterations, 10);
}

// A mirror sphere lit from straight above sends no light under itself: a walk from a valid path to a floor point
// beneath the sphere (across the silhouette of the reflecting cap) must fail without a result.
TEST(ManifoldWalk, TargetAcrossTheSilhouetteFailsCleanly) {
    const auto scene = loadManifoldScene("mirror_sphere.xml");
    const ManifoldWalk walker(*scene);
    const std::vector<ManifoldVertex> chain = chainTowards(*scene, Vec3(0, 0, 4), Vec3(0.85, 0.1, 0.5), 1);
    ASSERT_EQ(chain.size(), 3u);
    const Vec3 end = chain[2].p;
    ASSERT_LT(end.z, -2.9);
    // A nearby target is reachable from the same start.
    EXPECT_TRUE(walker.walk(chain, targetAt(*scene, Vec3(end.x - 0.2, end.y, -2.5), Vec3(0, 0, -1))).converged());
    const WalkResult result = walker.walk(chain, targetAt(*scene, Vec3(0.3, 0.2, -2.5), Vec3(0, 0, -1)));
    EXPECT_FALSE(result.converged());
    EXPECT_FALSE(result.stats.converged);
    EXPECT_TRUE(result.chain.empty());
    EXPECT_LE(result.stats.iterations, walker.parameters().maxIterations);
}

// The virtual plane ignores the scene at the end, so a walk can converge onto a target that x_{n-1} cannot see:
// plane_mirror.xml has an occluder on the last segment of the mirror-image path from (5, 4, 0.5) to (5, 7, 2).
TEST(ManifoldWalk, OccludedTargetIsRejected) {
    const auto scene = loadManifoldScene("plane_mirror.xml");
    const ManifoldWalk walker(*scene);
    const std::vector<ManifoldVertex> chain = chainTowards(*scene, Vec3(5, 4, 0.5), Vec3(5, 3, 0), 1);
    ASSERT_EQ(chain.size(), 3u);
    const WalkResult blocked = walker.walk(chain, targetAt(*scene, Vec3(5, 7, 1.9), Vec3(0, 0, 1)));
    EXPECT_EQ(blocked.status, WalkStatus::Occluded);
    EXPECT_TRUE(blocked.chain.empty());
    // Control: beside the occluder the same walk succeeds.
    EXPECT_TRUE(walker.walk(chain, targetAt(*scene, Vec3(6, 7, 1.9), Vec3(0, 0, 1))).converged());
}

// A directional light (FixedDirection start, §6.1) through the glass sphere: the walk moves the beam's position
// on its plane ⟂ d. The found ray must leave x_1 exactly along d, and Snell's law must hold at both refractions.
TEST(ManifoldWalk, DirectionalStartThroughGlassSphere) {
    const auto scene = loadManifoldScene("glass_sphere.xml");
    const ManifoldWalk walker(*scene, tight());
    const Vec3 d = normalize(Vec3(0.1, -0.05, -1));
    PCG32 rng(8, 1);
    int converged = 0;
    for (int trial = 0; trial < 20; ++trial) {
        const Vec3 x0 = Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 0) - d * 4.0;
        const auto hits = traceSpecular(*scene, x0, d, 2);
        ASSERT_TRUE(hits);
        std::vector<ManifoldVertex> chain = chainFrom(x0, *hits);
        chain[0] = ManifoldVertex::fixedDirection(x0, d);
        const Vec3 end = hits->back().p;
        const ManifoldVertex target = floorTargetNear(*scene, end, 0.1, rng);
        const WalkResult result = walker.walk(chain, target);
        if (!result.converged()) continue;
        ++converged;
        EXPECT_EQ(result.stats.chainSize, 3);
        EXPECT_LT(cross(normalize(result.chain[1].p - result.chain[0].p), d).length(), 1e-9);
        EXPECT_NEAR(dot(result.chain[0].p - x0, d), 0.0, 1e-9);
        for (size_t i = 1; i <= 2; ++i) EXPECT_LT(opticsResidual(result.chain, i), 1e-9);
    }
    EXPECT_GE(converged, 18);
}

// Offset manifolds (§6.6): a path through the plane refractor that refracts about a tilted microfacet normal keeps
// its offset o = T^T h while walking; the found vertex satisfies c = o (not Snell's law about the surface normal),
// the iteration still converges quadratically (the plane's tangent frame is constant, so ∇C is exact for S_o),
// and the reverse walk returns to the start.
TEST(ManifoldWalk, PlaneRefractorOffsetManifold) {
    const auto scene = loadManifoldScene("plane_refractor.xml");
    const ManifoldWalk walker(*scene, tight());
    PCG32 rng(12, 1);
    for (int trial = 0; trial < 20; ++trial) {
        const Vec3 x1(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.5, 1.5));
        const Vec3 tilt(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), 0);
        const auto hits =
            traceSpecular(*scene, x1, normalize(Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), 0) - x1), 1, tilt);
        ASSERT_TRUE(hits);
        const std::vector<ManifoldVertex> chain = chainFrom(x1, *hits, false);
        ASSERT_GT(chain[1].offset.x * chain[1].offset.x + chain[1].offset.y * chain[1].offset.y, 1e-6);
        const Vec3 end = hits->back().p;
        const Vec3 t(end.x + uniform(rng, -1, 1), end.y + uniform(rng, -1, 1), -1.5);
        const WalkResult forward = walker.walk(chain, targetAt(*scene, t, Vec3(0, 0, -1)));
        ASSERT_TRUE(forward.converged());
        EXPECT_LE(forward.stats.iterations, 6);
        const Vec2 c = *constraintValue(forward.chain[0], forward.chain[1], forward.chain[2]);
        EXPECT_NEAR(c.x, chain[1].offset.x, 1e-12);
        EXPECT_NEAR(c.y, chain[1].offset.y, 1e-12);
        EXPECT_GT(opticsResidual(forward.chain, 1), 1e-3);  // off the ideal specular manifold
        const WalkResult back = walker.walk(forward.chain, chain.back());
        ASSERT_TRUE(back.converged());
        EXPECT_LT((back.chain[1].p - chain[1].p).length(), 1e-9);
    }
}

// Offset manifolds on a curved shape: two refractions through the glass sphere about tilted microfacet normals
// (glossy vertices). The sphere's chart (spherical coordinates) turns within the tangent plane as the point moves;
// the glossy vertices' continuous frame (specular_constraint.h) is differentiated exactly, so the iteration
// converges quadratically here too: a small move of the end takes a few iterations to reach ε = 1e-13 (with the
// chart's frame and its turning left out of ∇C it converged linearly and hit the iteration limit), keeps every
// offset, and the reverse walk returns.
TEST(ManifoldWalk, GlassSphereOffsetManifoldConvergesQuadratically) {
    const auto scene = loadManifoldScene("glass_sphere.xml");
    const ManifoldWalk walker(*scene, tight());
    PCG32 rng(14, 2);
    int walked = 0;
    for (int trial = 0; trial < 400 && walked < 40; ++trial) {
        const Vec3 x1(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 4);
        const Vec3 aim(uniform(rng, -0.6, 0.6), uniform(rng, -0.6, 0.6), 0);
        const Vec3 tilt(uniform(rng, -0.15, 0.15), uniform(rng, -0.15, 0.15), uniform(rng, -0.15, 0.15));
        const auto hits = traceSpecular(*scene, x1, normalize(aim - x1), 2, tilt);
        if (!hits || hits->back().p.z > -2.9) continue;
        const std::vector<ManifoldVertex> chain = chainFrom(x1, *hits, false);
        ++walked;
        const WalkResult forward = walker.walk(chain, floorTargetNear(*scene, hits->back().p, 0.05, rng));
        ASSERT_EQ(forward.status, WalkStatus::Converged);
        EXPECT_LE(forward.stats.iterations, 6);
        for (size_t i = 1; i <= 2; ++i) {
            ASSERT_TRUE(chain[i].glossy);
            // Recomputed from the vertex positions, whose sphere intersections carry rounding of about 1e-12.
            const Vec2 c = *constraintValue(forward.chain[i - 1], forward.chain[i], forward.chain[i + 1]);
            EXPECT_NEAR(c.x, chain[i].offset.x, 1e-10);
            EXPECT_NEAR(c.y, chain[i].offset.y, 1e-10);
        }
        const WalkResult back = walker.walk(forward.chain, chain.back());
        ASSERT_EQ(back.status, WalkStatus::Converged);
        EXPECT_LE(back.stats.iterations, 6);
        for (size_t i = 1; i <= 2; ++i) EXPECT_LT((back.chain[i].p - chain[i].p).length(), 1e-9);
    }
    EXPECT_EQ(walked, 40);
}

// The configuration a corrector trace must keep is the shape (with its BSDF and side), not the triangle: on a
// flat-shaded mesh (Mitsuba's cube: one normal per face) the trace may cross to the other triangle of a face and
// onto another face, and a trace that meets another shape is refused.
TEST(ManifoldWalk, AnyTriangleOfTheShapeKeepsTheConfiguration) {
    const std::string dir = tempDir("manifold_facets");
    const auto scene = loadScene(writeFile(dir, "scene.xml", R"(<scene version="0.6.0">
        <sensor type="perspective"><transform name="toWorld"><lookat origin="0,-12,6" target="0,0,0" up="0,0,1"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <shape type="cube"><bsdf type="conductor"/></shape>
        <shape type="sphere"><point name="center" x="2" y="0.2" z="1.1"/><float name="radius" value="0.2"/>
            <bsdf type="conductor"/></shape>
        <shape type="sphere"><float name="radius" value="20"/><bsdf type="diffuse"/></shape>
    </scene>)"));
    const ManifoldWalk walker(*scene);
    const Vec3 x1(3, 0.2, 2);
    // The chain x_1 -> mirror point q -> the enclosing sphere.
    const auto chainVia = [&](const Vec3 &q) {
        const auto hits = traceSpecular(*scene, x1, normalize(q - x1), 1);
        EXPECT_TRUE(hits);
        return chainFrom(x1, *hits);
    };
    const auto retrace = [&](const std::vector<ManifoldVertex> &chain, const Vec3 &q) {
        return walker.propagate(chain, x1, normalize(q - x1), nullptr);
    };
    // Two points of the face x = 1 on either side of its diagonal y = z, so on different triangles.
    const Vec3 corner(1, 0.8, -0.8), opposite(1, -0.8, 0.8);
    const std::vector<ManifoldVertex> a = chainVia(corner);
    ASSERT_EQ(a.size(), 3u);
    const auto sameFace = retrace(a, opposite);
    ASSERT_TRUE(sameFace);
    EXPECT_NE((*sameFace)[1].its.primIndex, a[1].its.primIndex);
    // The top face z = 1, met by a ray that passes above the edge of the face x = 1.
    const auto otherFace = retrace(a, Vec3(0.8, 0.2, 1));
    ASSERT_TRUE(otherFace);
    EXPECT_NEAR((*otherFace)[1].its.shFrame.n.z, 1.0, 1e-12);
    // The small mirror sphere between x_1 and the cube is another shape.
    EXPECT_FALSE(retrace(a, Vec3(1, 0.2, 0.2)));
}

TEST(ManifoldWalk, VirtualPlaneIsSymmetric) {
    PCG32 rng(9, 9);
    for (int trial = 0; trial < 1000; ++trial) {
        const Vec3 p(uniform(rng, -3, 3), uniform(rng, -3, 3), uniform(rng, -3, 3));
        const Vec3 q = p + warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()}) * uniform(rng, 1e-3, 2);
        const Vec3 n = warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()});
        const Vec3 m = warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()});
        const std::optional<ManifoldVertex> a = virtualPlane(p, n, q, m), b = virtualPlane(q, m, p, n);
        ASSERT_TRUE(a && b);
        EXPECT_NEAR(std::abs(dot(a->ng, b->ng)), 1.0, 1e-14);
        // Both ends lie on the plane, whose chart is orthonormal and perpendicular to its normal.
        EXPECT_NEAR(dot(q - p, a->ng), 0.0, 1e-12);
        EXPECT_NEAR(dot(a->dpdu, a->dpdv), 0.0, 1e-14);
        EXPECT_NEAR(dot(a->dpdu, a->ng), 0.0, 1e-14);
        EXPECT_NEAR(a->dpdu.length(), 1.0, 1e-14);
        EXPECT_EQ(a->p, p);
        EXPECT_EQ(b->p, q);
    }
    // The normal sum n + n' parallel to the step leaves no plane containing both ends.
    EXPECT_FALSE(virtualPlane(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 0, 1), Vec3(0, 0, 1)));
}

// |∂x_n/∂s × ∂x_n/∂t| by central differences, where rayAt(s, t) gives the origin and direction of the traced
// ray: the area at x_n swept per unit (s, t).
template <typename RayAt>
double tracedArea(const Scene &scene, int specular, const RayAt &rayAt) {
    constexpr double h = 1e-6;
    const auto endAt = [&](double s, double t) {
        const auto [o, d] = rayAt(s, t);
        const auto traced = traceSpecular(scene, o, d, specular);
        EXPECT_TRUE(traced);
        return traced ? traced->back().p : Vec3(0.0);
    };
    const Vec3 ds = (endAt(h, 0) - endAt(-h, 0)) / (2 * h), dt = (endAt(0, h) - endAt(0, -h)) / (2 * h);
    return cross(ds, dt).length();
}

// §6.3: G(x_1 <-> … <-> x_n) of a refractor is the solid angle at the point x_1 per unit area at x_n. Central
// differences of the traced end over a square of directions around the chain's first edge (d ω = ds dt at the
// centre) give the reference 1 / |∂x_n/∂s × ∂x_n/∂t|.
void checkRefractorGeometryTerm(const Scene &scene, const Vec3 &x1, const Vec3 &aim, int specular) {
    const Vec3 w0 = normalize(aim - x1);
    const auto hits = traceSpecular(scene, x1, w0, specular);
    ASSERT_TRUE(hits);
    const std::optional<double> g = generalizedGeometry(chainFrom(x1, *hits));
    ASSERT_TRUE(g);
    const Frame frame(w0);
    const double area = tracedArea(scene, specular, [&](double s, double t) {
        return std::make_pair(x1, normalize(w0 + frame.s * s + frame.t * t));
    });
    EXPECT_NEAR(*g * area, 1.0, 1e-6) << "G " << *g << " reference " << 1 / area;
}

// For a directional start the generalized G is the beam's cross-section area per unit area at x_n: central
// differences of the traced end over the start's position on its plane ⟂ d.
void checkDirectionalGeometryTerm(const Scene &scene, const Vec3 &x0, const Vec3 &d, int specular) {
    const auto hits = traceSpecular(scene, x0, d, specular);
    ASSERT_TRUE(hits);
    std::vector<ManifoldVertex> chain = chainFrom(x0, *hits);
    chain[0] = ManifoldVertex::fixedDirection(x0, d);
    const std::optional<double> g = generalizedGeometry(chain);
    ASSERT_TRUE(g);
    const Frame frame(d);
    const double area = tracedArea(
        scene, specular, [&](double s, double t) { return std::make_pair(x0 + frame.s * s + frame.t * t, d); });
    EXPECT_NEAR(*g * area, 1.0, 1e-6);
    // The reversed chain (directional end last, its refractions' eta inverted) gives the same G.
    EXPECT_NEAR(*generalizedGeometry(reversedChain(chain)) / *g, 1.0, 1e-12);
}

// Through a refraction the two directions of the generalized geometry term differ (§6.3, étendue):
// generalizedGeometry(x_1 … x_n) is the projected solid angle at x_1 per unit area at x_n, the reversed chain's
// the projected solid angle at x_n per unit area at x_1, and η_1² dA_1 dΩ⊥_1 = η_n² dA_n dΩ⊥_n makes their ratio
// (η_n / η_1)². x_1 lies on a (virtual) downward-facing surface in the air above the plane refractor and x_n on
// the receiver in the glass; each direction is checked against a traced finite-difference reference.
TEST(ManifoldWalk, RefractorGeometryTermDirectionsDifferByTheEtendueFactor) {
    const auto scene = loadManifoldScene("plane_refractor.xml");
    PCG32 rng(8, 3);
    for (int trial = 0; trial < 10; ++trial) {
        const Vec3 x1(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.5, 2));
        const Vec3 w1 = normalize(Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), 0) - x1);
        const auto hits = traceSpecular(*scene, x1, w1, 1);
        ASSERT_TRUE(hits);
        std::vector<ManifoldVertex> chain = chainFrom(x1, *hits);
        ManifoldVertex &start = chain[0];
        start.type = ManifoldVertexType::Surface;
        start.ng = start.n = Vec3(0, 0, -1);
        coordinateSystem(start.ng, start.dpdu, start.dpdv);
        const std::optional<double> fromAir = generalizedGeometry(chain),
                                    fromGlass = generalizedGeometry(reversedChain(chain));
        ASSERT_TRUE(fromAir && fromGlass);
        EXPECT_NEAR(*fromAir / *fromGlass, 1.5 * 1.5, 1e-9);

        // From x_1: |cos θ_1| over the area at x_n swept per unit solid angle.
        const Frame f1(w1);
        const double areaBelow = tracedArea(
            *scene, 1, [&](double s, double t) { return std::make_pair(x1, normalize(w1 + f1.s * s + f1.t * t)); });
        EXPECT_NEAR(*fromAir * areaBelow / std::abs(w1.z), 1.0, 1e-6);
        // From x_n: rays refracted up through the interface to the plane of x_1.
        const Vec3 xn = hits->back().p, wn = normalize(hits->front().p - xn);
        const Frame fn(wn);
        constexpr double h = 1e-6;
        const auto landing = [&](double s, double t) {
            const Vec3 d = normalize(wn + fn.s * s + fn.t * t);
            Intersection its;
            EXPECT_TRUE(scene->intersect(Ray(xn, d, scene->epsilonAt(xn)), its));
            const Vec3 up = *bounce(d, its.n, 1.5);
            return its.p + up * ((x1.z - its.p.z) / up.z);
        };
        const Vec3 ds = (landing(h, 0) - landing(-h, 0)) / (2 * h), dt = (landing(0, h) - landing(0, -h)) / (2 * h);
        EXPECT_NEAR(*fromGlass * cross(ds, dt).length() / std::abs(wn.z), 1.0, 1e-6);
    }
}

TEST(ManifoldWalk, RefractorGeometryTermMatchesTracedSolidAngleRatio) {
    const auto plane = loadManifoldScene("plane_refractor.xml");
    const auto sphere = loadManifoldScene("glass_sphere.xml");
    PCG32 rng(6, 6);
    for (int trial = 0; trial < 10; ++trial) {
        checkRefractorGeometryTerm(*plane, Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, 0.5, 2)),
                                   Vec3(uniform(rng, -1, 1), uniform(rng, -1, 1), 0), 1);
        checkRefractorGeometryTerm(*sphere, Vec3(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), 4),
                                   Vec3(uniform(rng, -0.6, 0.6), uniform(rng, -0.6, 0.6), 0), 2);
        const Vec3 d = normalize(Vec3(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), -1));
        checkDirectionalGeometryTerm(*sphere, Vec3(uniform(rng, -0.6, 0.6), uniform(rng, -0.6, 0.6), 0) - d * 4.0, d,
                                     2);
    }
}

}  // namespace
}  // namespace pf::test
