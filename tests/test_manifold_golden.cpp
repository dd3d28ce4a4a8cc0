// Golden checks of the manifold-exploration differential geometry (ALGORITHMS.md §6.1-6.3, §9.2): the worked
// example of [TR §3.3] (∇C blocks, T_S, G = 1/48), central finite differences of every constraint row on random
// configurations (reflection and eta = 1.5 refraction, shading normals tilted off the chart, the fixed-direction
// endpoint row), the offset-manifold microfacet normal and scattering about it (§6.6), the planar-mirror
// unfolded geometry term (§6.3), and the block-tridiagonal LU against dense elimination.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>
#include <vector>

#include "core/frame.h"
#include "core/rng.h"
#include "core/warp.h"
#include "manifold/block_tridiagonal.h"
#include "manifold/chain_jacobian.h"
#include "manifold/generalized_geometry.h"
#include "manifold/specular_constraint.h"
#include "path/vertex.h"

namespace pf::test {
namespace {

Vec3 randomDirection(PCG32 &rng) { return warp::squareToUniformSphere({rng.nextDouble(), rng.nextDouble()}); }
double uniform(PCG32 &rng, double lo, double hi) { return lo + (hi - lo) * rng.nextDouble(); }

// An unconstrained vertex at p with the orthonormal chart of a plane with normal n.
ManifoldVertex planeVertex(const Vec3 &p, const Vec3 &n) {
    ManifoldVertex v;
    v.p = p;
    v.ng = v.n = n;
    coordinateSystem(n, v.dpdu, v.dpdv);
    return v;
}

// A random constrained vertex: an orthonormal chart, a shading normal tilted off the chart's normal by up to
// ~0.3 rad, and normal derivatives perpendicular to it (derivatives of a unit vector).
ManifoldVertex randomSpecular(PCG32 &rng, Scattering scattering, double eta) {
    ManifoldVertex v;
    v.p = Vec3(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3));
    v.ng = randomDirection(rng);
    coordinateSystem(v.ng, v.dpdu, v.dpdv);
    const double angle = uniform(rng, 0, 2 * kPi);
    const Vec3 e1 = v.dpdu * std::cos(angle) + v.dpdv * std::sin(angle);
    v.dpdv = cross(v.ng, e1);
    v.dpdu = e1;
    v.n = normalize(v.ng + randomDirection(rng) * 0.3);
    for (Vec3 *d : {&v.dndu, &v.dndv}) {
        const Vec3 r = randomDirection(rng) * uniform(rng, 0.2, 2.0);
        *d = r - v.n * dot(r, v.n);
    }
    v.scattering = scattering;
    v.eta = eta;
    return v;
}

// Cycles through reflection, refraction into glass (eta = 1.5) and out of it (1 / 1.5).
std::pair<Scattering, double> opticsOfTrial(int trial) {
    switch (trial % 3) {
        case 0:
            return {Scattering::Reflection, 1.0};
        case 1:
            return {Scattering::Refraction, 1.5};
        default:
            return {Scattering::Refraction, 1.0 / 1.5};
    }
}

// Moves vertex v by (du, dv) in its chart with the first-order model of §6.2: p + u dp/du + v dp/dv, the normal
// n + u dn/du + v dn/dv renormalized; the partials stay.
ManifoldVertex moved(const ManifoldVertex &v, double du, double dv) {
    ManifoldVertex w = v;
    w.p = v.p + v.dpdu * du + v.dpdv * dv;
    if (!v.ng.isZero() && v.type != ManifoldVertexType::FixedDirection)
        w.n = normalize(v.n + v.dndu * du + v.dndv * dv);
    return w;
}

void expectMat2Near(const Mat2 &a, const Mat2 &b, double tol, const char *what) {
    for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 2; ++c) EXPECT_NEAR(a(r, c), b(r, c), tol) << what << " (" << r << "," << c << ")";
}

// Central differences of c_i with respect to the chart of vertex `which` (0 = prev, 1 = self, 2 = next), with
// step h.
Mat2 centralDifference(const ManifoldVertex &prev, const ManifoldVertex &v, const ManifoldVertex &next, int which,
                       double h) {
    Mat2 fd;
    for (int col = 0; col < 2; ++col) {
        Vec2 values[2];
        for (int side = 0; side < 2; ++side) {
            const double step = side == 0 ? h : -h;
            ManifoldVertex a = prev, b = v, c = next;
            ManifoldVertex &target = which == 0 ? a : (which == 1 ? b : c);
            target = moved(target, col == 0 ? step : 0.0, col == 1 ? step : 0.0);
            values[side] = *constraintValue(a, b, c);
        }
        fd(0, col) = (values[0].x - values[1].x) / (2 * h);
        fd(1, col) = (values[0].y - values[1].y) / (2 * h);
    }
    return fd;
}

// Richardson's extrapolation of two central differences (error O(h^4) instead of O(h^2)), so that the
// comparison tolerance stays far below any error of a derivative term.
Mat2 finiteDifference(const ManifoldVertex &prev, const ManifoldVertex &v, const ManifoldVertex &next, int which) {
    constexpr double h = 1e-4;
    return (centralDifference(prev, v, next, which, h / 2) * 4.0 - centralDifference(prev, v, next, which, h)) *
           (1.0 / 3.0);
}

double maxAbs(const Mat2 &m) {
    return std::max({std::abs(m(0, 0)), std::abs(m(0, 1)), std::abs(m(1, 0)), std::abs(m(1, 1))});
}

TEST(ManifoldGolden, WorkedExampleOfTheTechnicalReport) {
    // [TR §3.3]: x1, x3 on planes with normal (0,-1,0); x2 on a mirror cylinder along z.
    const ManifoldVertex x1 = planeVertex(Vec3(-1, 2, 0), Vec3(0, -1, 0));
    const ManifoldVertex x3 = planeVertex(Vec3(1, 2, 0), Vec3(0, -1, 0));
    ManifoldVertex x2;
    x2.p = Vec3(0, 1, 0);
    x2.ng = x2.n = Vec3(0, 1, 0);
    x2.dpdu = Vec3(1, 0, 0);
    x2.dpdv = Vec3(0, 0, 1);
    x2.dndu = Vec3(1, 0, 0);
    x2.scattering = Scattering::Reflection;

    // The example's charts: dp/du = (-1,0,0) at x_1 and (1,0,0) at x_3, dp/dv = (0,0,1) at both.
    std::vector<ManifoldVertex> chain = {x1, x2, x3};
    chain[0].dpdu = Vec3(-1, 0, 0);
    chain[2].dpdu = Vec3(1, 0, 0);
    chain[0].dpdv = chain[2].dpdv = Vec3(0, 0, 1);
    const std::optional<ConstraintDerivatives> d = constraintDerivatives(chain[0], chain[1], chain[2]);
    ASSERT_TRUE(d);
    expectMat2Near(d->prev, Mat2(-0.25, 0, 0, 0.5), 1e-15, "B_1");
    expectMat2Near(d->self, Mat2(-1.5, 0, 0, -1), 1e-15, "A");
    expectMat2Near(d->next, Mat2(0.25, 0, 0, 0.5), 1e-15, "B_3");

    ChainJacobian jacobian;
    ASSERT_TRUE(jacobian.build(chain));
    const TangentSpace ts = tangentSpace(jacobian);
    ASSERT_EQ(ts.wrtFirst.size(), 1u);
    expectMat2Near(ts.wrtFirst[0], Mat2(-1.0 / 6, 0, 0, 0.5), 1e-15, "T_S (x_1 columns)");
    expectMat2Near(ts.wrtLast[0], Mat2(1.0 / 6, 0, 0, 0.5), 1e-15, "T_S (x_3 columns)");
    const std::optional<double> g = generalizedGeometry(chain);
    ASSERT_TRUE(g);
    EXPECT_NEAR(*g, 1.0 / 48, 1e-15);
}

// Every block of every row against central differences, for reflection and for refraction with eta = 1.5 and
// 1/1.5, on configurations with tilted shading normals and curved surfaces, in the chart's frame of ideal
// specular vertices and in the continuous frame of glossy ones (specular_constraint.h), whose turning with the
// normal the diagonal block must include.
TEST(ManifoldGolden, ConstraintRowsMatchFiniteDifferences) {
    PCG32 rng(11, 3);
    int checked = 0;
    for (int trial = 0; trial < 600; ++trial) {
        const auto [scattering, eta] = opticsOfTrial(trial / 2);
        ManifoldVertex v = randomSpecular(rng, scattering, eta);
        v.glossy = trial % 2 == 1;
        // Neighbours at distance 1-3 with random orthonormal charts; the previous one possibly a surface vertex
        // with a constrained row of its own (only its chart matters here).
        const ManifoldVertex prev = planeVertex(v.p + randomDirection(rng) * uniform(rng, 1, 3), randomDirection(rng));
        const ManifoldVertex next = planeVertex(v.p + randomDirection(rng) * uniform(rng, 1, 3), randomDirection(rng));
        // Stay away from a nearly vanishing ω_i + eta ω_o, where the constraint is ill-conditioned.
        if ((normalize(prev.p - v.p) + normalize(next.p - v.p) * eta).length() < 0.2) continue;
        const std::optional<ConstraintDerivatives> d = constraintDerivatives(prev, v, next);
        ASSERT_TRUE(d);
        const Mat2 analytic[3] = {d->prev, d->self, d->next};
        for (int which = 0; which < 3; ++which) {
            const Mat2 fd = finiteDifference(prev, v, next, which);
            const double scale = std::max(1.0, maxAbs(analytic[which]));
            expectMat2Near(analytic[which], fd, 1e-8 * scale, which == 0 ? "prev" : (which == 1 ? "self" : "next"));
        }
        ++checked;
    }
    EXPECT_GT(checked, 500);
}

// The glossy frame is a function of the shading normal alone: two charts of the same tangent plane (two
// triangles of a mesh meeting at an edge, or a turned parameterization) give the same offset, while the chart's
// frame of ideal vertices turns with the chart.
TEST(ManifoldGolden, GlossyFrameDependsOnTheNormalAlone) {
    PCG32 rng(31, 4);
    for (int trial = 0; trial < 100; ++trial) {
        ManifoldVertex v = randomSpecular(rng, Scattering::Reflection, 1.0);
        const ManifoldVertex prev = ManifoldVertex::fixedPosition(v.p + randomDirection(rng) * 2.0);
        const ManifoldVertex next = ManifoldVertex::fixedPosition(v.p + randomDirection(rng) * 1.5);
        ManifoldVertex turned = v;
        const double angle = uniform(rng, 0.1, 3.0);
        turned.dpdu = v.dpdu * std::cos(angle) + v.dpdv * std::sin(angle);
        turned.dpdv = v.dpdv * std::cos(angle) - v.dpdu * std::sin(angle);
        const std::optional<Vec2> chart = constraintValue(prev, v, next),
                                  chartTurned = constraintValue(prev, turned, next);
        ASSERT_TRUE(chart && chartTurned);
        const Vec2 change = *chart - *chartTurned;
        EXPECT_GT(std::hypot(change.x, change.y), 1e-6 * std::hypot(chart->x, chart->y));
        v.glossy = turned.glossy = true;
        const std::optional<Vec2> glossy = constraintValue(prev, v, next),
                                  glossyTurned = constraintValue(prev, turned, next);
        ASSERT_TRUE(glossy && glossyTurned);
        EXPECT_NEAR(glossy->x, glossyTurned->x, 1e-15);
        EXPECT_NEAR(glossy->y, glossyTurned->y, 1e-15);
        // It spans the shading tangent plane with an orthonormal frame: |o| is the sine of the angle between h and n.
        const Vec3 h = *generalizedHalfVector(prev, v, next);
        EXPECT_NEAR(std::hypot(glossy->x, glossy->y), cross(h, v.n).length(), 1e-12);
    }
}

// The fixed-direction endpoint row c_1 = T(x_1)^T γ(x_2 - x_1) of §6.1 (directional light, orthographic camera).
TEST(ManifoldGolden, FixedDirectionRowMatchesFiniteDifferences) {
    PCG32 rng(5, 8);
    for (int trial = 0; trial < 100; ++trial) {
        const Vec3 d = randomDirection(rng);
        const ManifoldVertex x1 = ManifoldVertex::fixedDirection(Vec3(uniform(rng, -1, 1), 0, 0), d);
        const ManifoldVertex x2 =
            planeVertex(x1.p + normalize(d + randomDirection(rng) * 0.3) * uniform(rng, 1, 4), randomDirection(rng));
        const std::optional<ConstraintDerivatives> deriv = constraintDerivatives(x1, x1, x2);
        ASSERT_TRUE(deriv);
        expectMat2Near(deriv->self, finiteDifference(x1, x1, x2, 1), 1e-8, "self");
        expectMat2Near(deriv->next, finiteDifference(x1, x1, x2, 2), 1e-8, "next");
    }
}

// §6.6: the offset o = T^T h with the sign of <h, n> recovers h exactly, and scattering ω_i about it reproduces
// ω_o (so the corrector stays on the offset manifold), for reflection and both refraction directions.
TEST(ManifoldGolden, OffsetManifoldRecoversTheMicrofacetNormal) {
    PCG32 rng(23, 1);
    int checked = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const auto [scattering, eta] = opticsOfTrial(trial);
        ManifoldVertex v = randomSpecular(rng, scattering, eta);
        const Vec3 wi = randomDirection(rng);
        // A physically consistent ω_o: scatter ω_i about a random microfacet normal m.
        const Vec3 m = normalize(v.n + randomDirection(rng) * 0.4);
        const std::optional<Vec3> wo = scatterAbout(wi, m, scattering, eta);
        if (!wo) continue;  // total internal reflection
        EXPECT_NEAR(wo->length(), 1.0, 1e-12);
        const ManifoldVertex prev = ManifoldVertex::fixedPosition(v.p + wi * 2.0);
        const ManifoldVertex next = ManifoldVertex::fixedPosition(v.p + *wo * 1.5);
        const Vec3 h = *generalizedHalfVector(prev, v, next);
        EXPECT_NEAR(std::abs(dot(h, m)), 1.0, 1e-12);
        v.offset = *constraintValue(prev, v, next);
        v.halfVectorAbove = dot(h, v.n) > 0;
        const std::optional<Vec3> recovered = microfacetNormal(v);
        ASSERT_TRUE(recovered);
        EXPECT_NEAR((*recovered - h).length(), 0.0, 1e-12);
        const Vec3 again = *scatterAbout(wi, *recovered, scattering, eta);
        EXPECT_NEAR((again - *wo).length(), 0.0, 1e-12);
        ++checked;
    }
    EXPECT_GT(checked, 200);
}

// §6.3 [CHK]: for a planar mirror the generalized geometry term is the ordinary one with the unfolded distance,
// |cos θ_1| |cos θ_3| / (d_1 + d_2)^2. Both forms of [TR eq. 9] (through x_1's and x_3's columns) are checked.
TEST(ManifoldGolden, PlanarMirrorUnfoldedGeometryTerm) {
    PCG32 rng(3, 9);
    for (int trial = 0; trial < 200; ++trial) {
        const Vec3 mirrorNormal = randomDirection(rng);
        const Vec3 origin(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
        Frame frame(mirrorNormal);
        const auto above = [&](double height) {
            return origin + frame.s * uniform(rng, -2, 2) + frame.t * uniform(rng, -2, 2) + mirrorNormal * height;
        };
        const Vec3 p1 = above(uniform(rng, 0.2, 2)), p3 = above(uniform(rng, 0.2, 2));
        // The reflection point: where the segment to x_3's mirror image crosses the plane.
        const double h1 = dot(p1 - origin, mirrorNormal), h3 = dot(p3 - origin, mirrorNormal);
        const Vec3 image = p3 - mirrorNormal * (2 * h3);
        const Vec3 p2 = p1 + (image - p1) * (h1 / (h1 + h3));
        ManifoldVertex x2 = planeVertex(p2, mirrorNormal);
        x2.scattering = Scattering::Reflection;
        const std::vector<ManifoldVertex> chain = {planeVertex(p1, randomDirection(rng)), x2,
                                                   planeVertex(p3, randomDirection(rng))};
        ASSERT_NEAR(constraintValue(chain[0], chain[1], chain[2])->x, 0.0, 1e-12);
        const double d1 = (p2 - p1).length(), d2 = (p3 - p2).length();
        const double expected =
            absDot(chain[0].ng, normalize(p2 - p1)) * absDot(chain[2].ng, normalize(p3 - p2)) / sqr(d1 + d2);
        const std::optional<double> g = generalizedGeometry(chain);
        ASSERT_TRUE(g);
        EXPECT_NEAR(*g / expected, 1.0, 1e-7);
        const std::vector<ManifoldVertex> reversed(chain.rbegin(), chain.rend());
        EXPECT_NEAR(*generalizedGeometry(reversed) / expected, 1.0, 1e-7);
    }
}

// Endpoints from path-space vertices (§6.1, §6.7): a pinhole (Dirac position) has no chart, an aperture or area
// light position gets an orthonormal chart around its normal, a medium vertex a chart facing its neighbour, and
// supernodes are not chain vertices. Surface vertices keep the orthonormalized chart of their intersection, with
// the same 2x2 map applied to the normal derivatives (dn/du, dn/dv of a sphere of radius 2: dp/du / 2).
TEST(ManifoldGolden, EndpointsFromPathVertices) {
    PathVertex pinhole;
    pinhole.type = VertexType::SensorNode;
    pinhole.its.p = Vec3(1, 2, 3);
    pinhole.ps.measure = Measure::Discrete;
    std::optional<ManifoldVertex> v = ManifoldVertex::endpoint(pinhole, Vec3(0, 0, 0));
    ASSERT_TRUE(v);
    EXPECT_EQ(v->type, ManifoldVertexType::FixedPosition);
    EXPECT_FALSE(v->hasChart());

    PathVertex aperture = pinhole;
    aperture.ps.measure = Measure::Area;
    aperture.ps.n = Vec3(0, 0, 2);
    v = ManifoldVertex::endpoint(aperture, Vec3(0, 0, 0));
    ASSERT_TRUE(v);
    EXPECT_EQ(v->type, ManifoldVertexType::Surface);
    EXPECT_NEAR(dot(v->ng, Vec3(0, 0, 1)), 1.0, 1e-15);
    EXPECT_NEAR(dot(v->dpdu, v->dpdv), 0.0, 1e-15);
    EXPECT_NEAR(dot(v->dpdu, v->ng), 0.0, 1e-15);

    PathVertex medium;
    medium.type = VertexType::Medium;
    medium.its.p = Vec3(1, 1, 1);
    v = ManifoldVertex::endpoint(medium, Vec3(1, 1, 4));
    ASSERT_TRUE(v);
    EXPECT_EQ(v->type, ManifoldVertexType::MediumEndpoint);
    EXPECT_NEAR(v->ng.z, 1.0, 1e-15);
    EXPECT_FALSE(ManifoldVertex::endpoint(PathVertex::sensorSupernode(), Vec3(0, 0, 0)));

    // A non-orthonormal parameterization of the sphere of radius 2 at (0, 0, 2): dp/du = (3, 0, 0),
    // dp/dv = (1, 1, 0); the outward normal's derivatives are dp/d(·) / 2.
    Intersection its;
    its.p = Vec3(0, 0, 2);
    its.n = Vec3(0, 0, 1);
    its.shFrame = Frame(its.n);
    its.dpdu = Vec3(3, 0, 0);
    its.dpdv = Vec3(1, 1, 0);
    its.dndu = its.dpdu * 0.5;
    its.dndv = its.dpdv * 0.5;
    v = ManifoldVertex::surface(its, Scattering::Reflection);
    ASSERT_TRUE(v);
    EXPECT_NEAR((v->dpdu - Vec3(1, 0, 0)).length(), 0.0, 1e-15);
    EXPECT_NEAR((v->dpdv - Vec3(0, 1, 0)).length(), 0.0, 1e-15);
    EXPECT_NEAR((v->dndu - Vec3(0.5, 0, 0)).length(), 0.0, 1e-15);
    EXPECT_NEAR((v->dndv - Vec3(0, 0.5, 0)).length(), 0.0, 1e-15);
    // Degenerate partials: a constrained vertex needs its normal derivatives and is refused.
    its.dpdv = its.dpdu * 2.0;
    EXPECT_FALSE(ManifoldVertex::surface(its, Scattering::Reflection));
    EXPECT_TRUE(ManifoldVertex::surface(its, Scattering::None));
}

// Dense reference: Gaussian elimination with partial pivoting on an n x n row-major matrix with `rhs` columns.
void denseSolve(std::vector<double> a, size_t n, std::vector<double> &b, size_t rhs, double &det) {
    det = 1;
    for (size_t k = 0; k < n; ++k) {
        size_t p = k;
        for (size_t r = k + 1; r < n; ++r)
            if (std::abs(a[r * n + k]) > std::abs(a[p * n + k])) p = r;
        if (p != k) {
            for (size_t c = 0; c < n; ++c) std::swap(a[k * n + c], a[p * n + c]);
            for (size_t c = 0; c < rhs; ++c) std::swap(b[k * rhs + c], b[p * rhs + c]);
            det = -det;
        }
        det *= a[k * n + k];
        for (size_t r = k + 1; r < n; ++r) {
            const double f = a[r * n + k] / a[k * n + k];
            for (size_t c = k; c < n; ++c) a[r * n + c] -= f * a[k * n + c];
            for (size_t c = 0; c < rhs; ++c) b[r * rhs + c] -= f * b[k * rhs + c];
        }
    }
    for (size_t k = n; k-- > 0;)
        for (size_t c = 0; c < rhs; ++c) {
            double s = b[k * rhs + c];
            for (size_t j = k + 1; j < n; ++j) s -= a[k * n + j] * b[j * rhs + c];
            b[k * rhs + c] = s / a[k * n + k];
        }
}

Mat2 randomMat2(PCG32 &rng) {
    return {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
}

TEST(ManifoldGolden, BlockTridiagonalMatchesDenseElimination) {
    PCG32 rng(17, 2);
    for (int trial = 0; trial < 200; ++trial) {
        const size_t blocks = 1 + trial % 9, n = 2 * blocks;
        BlockTridiagonal a(blocks);
        std::vector<double> dense(n * n, 0.0);
        const auto put = [&](size_t br, size_t bc, const Mat2 &m) {
            for (int i = 0; i < 2; ++i)
                for (int j = 0; j < 2; ++j) dense[(2 * br + i) * n + 2 * bc + j] = m(i, j);
        };
        for (size_t i = 0; i < blocks; ++i) {
            // Random blocks; a diagonal shift keeps the pivots away from singular (the generic case of ∇C).
            a.diag(i) = randomMat2(rng) + Mat2::identity() * 2.5;
            put(i, i, a.diag(i));
            if (i > 0) put(i, i - 1, a.lower(i) = randomMat2(rng));
            if (i + 1 < blocks) put(i, i + 1, a.upper(i) = randomMat2(rng));
        }
        ASSERT_TRUE(a.factorize());
        // A^{-1} against dense elimination with the identity as right-hand side.
        std::vector<double> inverse(n * n, 0.0);
        for (size_t i = 0; i < n; ++i) inverse[i * n + i] = 1;
        double det;
        denseSolve(dense, n, inverse, n, det);
        EXPECT_NEAR(a.determinant() / det, 1.0, 1e-12);
        std::vector<Vec2> x(blocks);
        std::vector<double> rhs(n);
        for (size_t i = 0; i < blocks; ++i)
            x[i] = Vec2(rhs[2 * i] = uniform(rng, -1, 1), rhs[2 * i + 1] = uniform(rng, -1, 1));
        a.solve(x);
        double unused;
        denseSolve(dense, n, rhs, 1, unused);
        for (size_t i = 0; i < blocks; ++i) {
            EXPECT_NEAR(x[i].x, rhs[2 * i], 1e-12);
            EXPECT_NEAR(x[i].y, rhs[2 * i + 1], 1e-12);
        }
        const size_t j = rng.nextUInt() % blocks;
        const std::vector<Mat2> column = a.inverseColumn(j);
        for (size_t i = 0; i < blocks; ++i)
            for (int r = 0; r < 2; ++r)
                for (int c = 0; c < 2; ++c) EXPECT_NEAR(column[i](r, c), inverse[(2 * i + r) * n + 2 * j + c], 1e-12);
        // The glossy determinant factor's submatrix of A^{-1}: every other block.
        std::vector<size_t> selected;
        for (size_t i = 0; i < blocks; i += 2) selected.push_back(i);
        const size_t m = 2 * selected.size();
        std::vector<double> sub(m * m);
        for (size_t r = 0; r < m; ++r)
            for (size_t c = 0; c < m; ++c)
                sub[r * m + c] = inverse[(2 * selected[r / 2] + r % 2) * n + 2 * selected[c / 2] + c % 2];
        std::vector<double> none;
        double subDet;
        denseSolve(sub, m, none, 0, subDet);
        EXPECT_NEAR(a.inverseSubmatrixDeterminant(selected) / subDet, 1.0, 1e-10);
    }
}

// A singular A makes the factorization fail instead of producing NaN: a rank-1 pivot, and a matrix whose blocks
// are all regular but whose second block row repeats the first (singular only through elimination).
TEST(ManifoldGolden, SingularBlockTridiagonalFails) {
    BlockTridiagonal rankOne(1);
    rankOne.diag(0) = Mat2(1, 2, 2, 4);
    EXPECT_FALSE(rankOne.factorize());
    EXPECT_FALSE(rankOne.factorized());

    BlockTridiagonal repeated(2);
    repeated.diag(0) = Mat2(2, 1, 1, 3);
    repeated.upper(0) = Mat2(1, 0, 0, 1);
    repeated.lower(1) = repeated.diag(0);
    repeated.diag(1) = repeated.upper(0);
    EXPECT_FALSE(repeated.factorize());

    // A chain whose A is singular, which ChainJacobian reports as such: a concave mirror sphere seen from its
    ManifoldVertex x2;
    x2.p = Vec3(0, 0, 0);
    x2.ng = x2.n = Vec3(0, 0, 1);
    x2.dpdu = Vec3(1, 0, 0);
    x2.dpdv = Vec3(0, 1, 0);
    x2.scattering = Scattering::Reflection;
    // centre (normal towards the centre, dn/du = -dp/du / R) reflects every ray back to the centre: with
    // x_1 = x_3 = centre, x_2 can slide freely (a fold of the wavefront) and A vanishes.
    const double radius = 2.0;
    x2.dndu = Vec3(-1 / radius, 0, 0);
    x2.dndv = Vec3(0, -1 / radius, 0);
    const std::vector<ManifoldVertex> chain = {planeVertex(Vec3(0, 0, radius), Vec3(0, 0, -1)), x2,
                                               planeVertex(Vec3(0, 0, radius), Vec3(0, 0, -1))};
    ChainJacobian jacobian;
    EXPECT_FALSE(jacobian.build(chain));
    EXPECT_TRUE(jacobian.singular);
    EXPECT_FALSE(generalizedGeometry(chain));
}

}  // namespace
}  // namespace pf::test
