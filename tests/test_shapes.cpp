// Shapes: ray hits against analytic answers; the differential geometry manifold exploration relies on
// (dp/du, dp/dv, dn/du, dn/dv against central finite differences of each shape's parameterization, with
// the normals at the perturbed points obtained by tracing rays); shading frames; direct sampling against
// its density (chi-square); uniform area sampling; the mesh readers (OBJ, PLY ascii and binary, Mitsuba
// serialized v3 and v4), their handling of corrupt files; instancing; the BSDF and emitter a shape gets.
#include <gtest/gtest.h>
#include <zlib.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <iterator>

#include "bsdf/bsdf.h"
#include "emitter/emitter.h"
#include "manifold/manifold_vertex.h"
#include "scene/plugins.h"
#include "scene/scene.h"
#include "shape/trianglemesh.h"
#include "support/chi2.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

const SourceLocation kLoc{"test.xml", 1};
constexpr int kChi2Tests = 11;  // chi-square tests in this file, for the multiple-test correction

Properties shapeProps(const std::string &plugin) { return Properties(ObjectKind::Shape, plugin, kLoc); }
void setFloat(Properties &p, const std::string &n, double v) { p.set(n, Properties::Type::Float, v, kLoc); }
void setBool(Properties &p, const std::string &n, bool v) { p.set(n, Properties::Type::Boolean, v, kLoc); }
void setInt(Properties &p, const std::string &n, int64_t v) { p.set(n, Properties::Type::Integer, v, kLoc); }
void setString(Properties &p, const std::string &n, const std::string &v) {
    p.set(n, Properties::Type::String, v, kLoc);
}
void setPoint(Properties &p, const std::string &n, const Vec3 &v) { p.set(n, Properties::Type::Point, v, kLoc); }
void setTransform(Properties &p, const std::string &n, const Transform &t) {
    p.set(n, Properties::Type::Transform, t, kLoc);
}

std::shared_ptr<Shape> makeShape(const Properties &p, const LoadContext &ctx = {}) {
    auto object = (*findPlugin(ObjectKind::Shape, p.pluginName()))(p, ctx);
    p.checkAllUsed();
    return std::dynamic_pointer_cast<Shape>(object);
}

std::unique_ptr<Scene> makeScene(const std::vector<std::shared_ptr<Shape>> &shapes) {
    auto scene = std::make_unique<Scene>();
    for (const auto &s : shapes) scene->addShape(s);
    const Properties sensor(ObjectKind::Sensor, "perspective", kLoc);
    scene->setSensor(std::dynamic_pointer_cast<Sensor>((*findPlugin(ObjectKind::Sensor, "perspective"))(sensor, {})));
    scene->finalize();
    return scene;
}

void expectVecNear(const Vec3 &a, const Vec3 &b, double tol, const std::string &what) {
    EXPECT_LE((a - b).length(), tol) << what << ": " << a << " vs " << b;
}

// ---------------------------------------------------------------------------------------------------
// Ray hits against analytic answers

TEST(ShapeHits, Sphere) {
    Properties p = shapeProps("sphere");
    setPoint(p, "center", Vec3(1, 2, 3));
    setFloat(p, "radius", 2.0);
    auto scene = makeScene({makeShape(p)});
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(1, 2, 10), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 5.0, 1e-12);
    expectVecNear(its.p, Vec3(1, 2, 5), 1e-12, "p");
    expectVecNear(its.n, Vec3(0, 0, 1), 1e-12, "n");
    expectVecNear(its.toWorld(its.wi), Vec3(0, 0, 1), 1e-12, "wi");
    // From the centre: the far root, normal still outward.
    ASSERT_TRUE(scene->intersect(Ray(Vec3(1, 2, 3), Vec3(1, 0, 0)), its));
    EXPECT_NEAR(its.t, 2.0, 1e-12);
    expectVecNear(its.n, Vec3(1, 0, 0), 1e-12, "n inside");
    EXPECT_FALSE(scene->intersect(Ray(Vec3(3.01, 2, 10), Vec3(0, 0, -1)), its));
    EXPECT_FALSE(scene->intersect(Ray(Vec3(1, 2, 10), Vec3(0, 0, -1), 0, 4.9), its));
    EXPECT_TRUE(scene->occluded(Ray(Vec3(1, 2, 10), Vec3(0, 0, -1), 0, 5.1)));
    EXPECT_FALSE(scene->occluded(Ray(Vec3(1, 2, 10), Vec3(0, 0, -1), 0, 4.9)));

    Properties f = shapeProps("sphere");
    setBool(f, "flipNormals", true);
    auto flipped = makeScene({makeShape(f)});
    ASSERT_TRUE(flipped->intersect(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)), its));
    expectVecNear(its.n, Vec3(0, 0, -1), 1e-12, "flipped n");
    EXPECT_GT(dot(its.shFrame.n, its.n), 0.0);
}

// A small sphere far away: the double-precision callback and fillIntersection keep the hit exact although
// Embree's ray is single precision.
TEST(ShapeHits, SmallDistantSphereIsExact) {
    Properties p = shapeProps("sphere");
    setPoint(p, "center", Vec3(1e4, 0.5, -0.25));
    setFloat(p, "radius", 1e-3);
    auto scene = makeScene({makeShape(p)});
    Intersection its;
    const Vec3 o(0, 0.5, -0.25);
    ASSERT_TRUE(scene->intersect(Ray(o, Vec3(1, 0, 0)), its));
    EXPECT_NEAR(its.t, 1e4 - 1e-3, 1e-9);
    EXPECT_NEAR((its.p - Vec3(1e4, 0.5, -0.25)).length(), 1e-3, 1e-12);
    // Just off the silhouette: a miss.
    EXPECT_FALSE(scene->intersect(Ray(o + Vec3(0, 1.001e-3, 0), Vec3(1, 0, 0)), its));
}

TEST(ShapeHits, Cylinder) {
    Properties p = shapeProps("cylinder");
    setPoint(p, "p0", Vec3(0, 0, 0));
    setPoint(p, "p1", Vec3(0, 0, 2));
    setFloat(p, "radius", 1.0);
    auto scene = makeScene({makeShape(p)});
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(5, 0, 1), Vec3(-1, 0, 0)), its));
    EXPECT_NEAR(its.t, 4.0, 1e-12);
    expectVecNear(its.n, Vec3(1, 0, 0), 1e-12, "n");
    EXPECT_NEAR(its.uv.y, 0.5, 1e-12);
    // Open ends: along the axis, and past the end, nothing is hit; from inside the side is hit with the
    // normal still pointing outward.
    EXPECT_FALSE(scene->intersect(Ray(Vec3(0.2, 0, -5), Vec3(0, 0, 1)), its));
    EXPECT_FALSE(scene->intersect(Ray(Vec3(5, 0, 2.01), Vec3(-1, 0, 0)), its));
    ASSERT_TRUE(scene->intersect(Ray(Vec3(0, 0, 1), Vec3(0, 1, 0)), its));
    EXPECT_NEAR(its.t, 1.0, 1e-12);
    expectVecNear(its.n, Vec3(0, 1, 0), 1e-12, "n from inside");
    // A ray entering through the open end hits the inside of the wall.
    ASSERT_TRUE(scene->intersect(Ray(Vec3(0, 0, 3), normalize(Vec3(1, 0, -1))), its));
    expectVecNear(its.p, Vec3(1, 0, 2), 1e-12, "p through the open end");
}

TEST(ShapeHits, Disk) {
    Properties p = shapeProps("disk");
    setTransform(p, "toWorld", Transform::translate(Vec3(0, 0, 1)) * Transform::scale(Vec3(2, 2, 2)));
    auto scene = makeScene({makeShape(p)});
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(1, 1, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 4.0, 1e-12);
    expectVecNear(its.n, Vec3(0, 0, 1), 1e-12, "n");
    EXPECT_NEAR(its.uv.x, std::sqrt(0.5), 1e-12);
    EXPECT_NEAR(its.uv.y, 0.125, 1e-12);
    EXPECT_FALSE(scene->intersect(Ray(Vec3(1.5, 1.5, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(scene->shapes()[0]->surfaceArea(), 4.0 * kPi, 1e-12);
}

TEST(ShapeHits, Rectangle) {
    Properties p = shapeProps("rectangle");
    setTransform(p, "toWorld", Transform::scale(Vec3(2, 3, 1)));
    auto scene = makeScene({makeShape(p)});
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(1.9, 2.9, 1), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 1.0, 1e-12);
    expectVecNear(its.n, Vec3(0, 0, 1), 1e-12, "n");
    EXPECT_NEAR(its.uv.x, (1.9 / 2 + 1) / 2, 1e-12);
    EXPECT_NEAR(its.uv.y, (2.9 / 3 + 1) / 2, 1e-12);
    EXPECT_FALSE(scene->intersect(Ray(Vec3(2.1, 0, 1), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(scene->shapes()[0]->surfaceArea(), 24.0, 1e-12);
    EXPECT_EQ(scene->primitiveCount(), 2u);

    Properties f = shapeProps("rectangle");
    setBool(f, "flipNormals", true);
    auto flipped = makeScene({makeShape(f)});
    ASSERT_TRUE(flipped->intersect(Ray(Vec3(0.5, 0.5, 1), Vec3(0, 0, -1)), its));
    expectVecNear(its.n, Vec3(0, 0, -1), 1e-12, "flipped n");
}

// Mitsuba 0.6 refuses a rectangle whose toWorld shears it (rectangle.cpp, configure(): its area
// |dpdu| |dpdv| and frame assume perpendicular edges). pathfarm renders the parallelogram (README,
// "Where pathfarm reads a scene differently from Mitsuba 0.6"): area |dpdu x dpdv|, uniform positions,
// the normal perpendicular to the plane on the side toWorld maps +z to.
TEST(ShapeHits, ShearedRectangleIsAParallelogram) {
    Matrix4 m = Matrix4::identity();
    m.m[0][1] = 0.75;  // x += 0.75 y: dpdu = (2, 0, 0), dpdv = (1.5, 2, 0)
    m.m[2][2] = 3.0;   // and a z scale, which must not tilt the normal
    Properties p = shapeProps("rectangle");
    setTransform(p, "toWorld", Transform(m));
    auto scene = makeScene({makeShape(p)});
    const Shape &rect = *scene->shapes()[0];
    EXPECT_NEAR(rect.surfaceArea(), 4.0, 1e-12);  // Mitsuba's formula would give 2 * 2.5 = 5
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(1.6, 0.9, 1), Vec3(0, 0, -1)), its));  // inside: x - 0.75 y = 0.925
    expectVecNear(its.n, Vec3(0, 0, 1), 1e-12, "n");
    EXPECT_FALSE(scene->intersect(Ray(Vec3(1.7, -0.9, 1), Vec3(0, 0, -1)), its));  // x - 0.75 y = 2.375 > 1
    for (const Vec2 u : {Vec2(0.1, 0.2), Vec2(0.5, 0.5), Vec2(0.9, 0.7)}) {
        PositionSample ps;
        rect.samplePosition(ps, u);
        expectVecNear(ps.n, Vec3(0, 0, 1), 1e-12, "sampled n");
        EXPECT_NEAR(ps.pdf, 0.25, 1e-12);
        EXPECT_LE(std::abs(ps.p.x - 0.75 * ps.p.y), 1.0 + 1e-12);
        EXPECT_LE(std::abs(ps.p.y), 1.0 + 1e-12);
    }
}

// A mirroring transform must not turn a faceted mesh inside out.
TEST(ShapeHits, MirroredCubeKeepsOutwardNormals) {
    Properties p = shapeProps("cube");
    setTransform(p, "toWorld", Transform::scale(Vec3(-1, 1, 1)));
    auto scene = makeScene({makeShape(p)});
    Intersection its;
    for (const Vec3 &n : {Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0, 0, 1)}) {
        ASSERT_TRUE(scene->intersect(Ray(n * 5.0 + Vec3(0.1, 0.2, 0.3) - n * dot(Vec3(0.1, 0.2, 0.3), n), -n), its));
        expectVecNear(its.n, n, 1e-12, "outward normal");
    }
}

TEST(ShapeHits, Cube) {
    Properties p = shapeProps("cube");
    setTransform(p, "toWorld", Transform::scale(Vec3(1, 2, 3)));
    auto scene = makeScene({makeShape(p)});
    EXPECT_EQ(scene->primitiveCount(), 12u);
    EXPECT_NEAR(scene->shapes()[0]->surfaceArea(), 2 * (4 * 2 * 3 + 4 * 1 * 3 + 4 * 1 * 2), 1e-9);
    const Vec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    const Vec3 half(1, 2, 3);
    for (const Vec3 &n : dirs) {
        const Vec3 offset(0.3 * half.x, -0.2 * half.y, 0.1 * half.z);
        const Vec3 tangentPart = offset - n * dot(offset, n);
        const double faceDist = std::abs(dot(n, half));
        Intersection its;
        ASSERT_TRUE(scene->intersect(Ray(tangentPart + n * 10.0, -n), its));
        EXPECT_NEAR(its.t, 10.0 - faceDist, 1e-12);
        expectVecNear(its.n, n, 1e-12, "face normal");
        // From inside, the face ahead, still with its outward normal.
        ASSERT_TRUE(scene->intersect(Ray(tangentPart, n), its));
        EXPECT_NEAR(its.t, faceDist, 1e-12);
        expectVecNear(its.n, n, 1e-12, "face normal from inside");
    }
}

// ---------------------------------------------------------------------------------------------------
// Differential geometry against finite differences

using Param = std::function<Vec3(const Vec2 &)>;

// Traces a ray at the surface point param(uv) along the surface normal (from finite differences).
Intersection hitAt(const Scene &scene, const Param &param, const Vec2 &uv) {
    const double h = 1e-6;
    const Vec3 p = param(uv);
    const Vec3 n = normalize(cross(param(Vec2(uv.x + h, uv.y)) - param(Vec2(uv.x - h, uv.y)),
                                   param(Vec2(uv.x, uv.y + h)) - param(Vec2(uv.x, uv.y - h))));
    Intersection its;
    EXPECT_TRUE(scene.intersect(Ray(p + n * 0.01, -n), its)) << "no hit at " << p;
    // The normal derivatives as the manifold code sees them (meshes compute them on request).
    if (its.normalDerivativesPending) its.shape->fillNormalDerivatives(its);
    return its;
}

double wrapDiff(double a, double b, bool periodic) {
    const double d = a - b;
    return periodic ? d - std::round(d) : d;
}

// Checks position, uv, dp/du, dp/dv, dn/du, dn/dv and the shading frame at param(uv). `periodicU` marks
// a u coordinate that wraps around (angles).
void checkDifferentials(const Scene &scene, const Param &param, const Vec2 &uv, bool periodicU, const char *what) {
    SCOPED_TRACE(what);
    const double h = 1e-5;
    const Intersection its = hitAt(scene, param, uv);
    ASSERT_TRUE(its.isValid());
    const double scale = 1.0 + its.p.length();
    expectVecNear(its.p, param(uv), 1e-10 * scale, "position");
    EXPECT_NEAR(wrapDiff(its.uv.x, uv.x, periodicU), 0.0, 1e-9) << "u";
    EXPECT_NEAR(its.uv.y, uv.y, 1e-9) << "v";

    const Vec2 du(h, 0), dv(0, h);
    const Vec3 dpduFD = (param(uv + du) - param(uv - du)) * (0.5 / h);
    const Vec3 dpdvFD = (param(uv + dv) - param(uv - dv)) * (0.5 / h);
    expectVecNear(its.dpdu, dpduFD, 1e-6 * (1.0 + dpduFD.length()), "dp/du");
    expectVecNear(its.dpdv, dpdvFD, 1e-6 * (1.0 + dpdvFD.length()), "dp/dv");

    // Shading normals at the neighbouring points, from the shape itself.
    const Intersection up = hitAt(scene, param, uv + du), um = hitAt(scene, param, uv - du);
    const Intersection vp = hitAt(scene, param, uv + dv), vm = hitAt(scene, param, uv - dv);
    EXPECT_NEAR(wrapDiff(up.uv.x, uv.x + h, periodicU), 0.0, 1e-9) << "u of the neighbour";
    const Vec3 dnduFD = (up.shFrame.n - um.shFrame.n) * (0.5 / h);
    const Vec3 dndvFD = (vp.shFrame.n - vm.shFrame.n) * (0.5 / h);
    expectVecNear(its.dndu, dnduFD, 1e-6 * (1.0 + dnduFD.length()), "dn/du");
    expectVecNear(its.dndv, dndvFD, 1e-6 * (1.0 + dndvFD.length()), "dn/dv");

    // Orthonormal, right-handed shading frame, tangent s along dp/du, normal on the geometric side.
    const Frame &f = its.shFrame;
    EXPECT_NEAR(f.s.length(), 1.0, 1e-12);
    EXPECT_NEAR(f.t.length(), 1.0, 1e-12);
    EXPECT_NEAR(f.n.length(), 1.0, 1e-12);
    EXPECT_NEAR(dot(f.s, f.t), 0.0, 1e-12);
    EXPECT_NEAR(dot(f.s, f.n), 0.0, 1e-12);
    expectVecNear(cross(f.s, f.t), f.n, 1e-12, "s x t = n");
    EXPECT_GT(dot(f.n, its.n), 0.0);
    EXPECT_NEAR(dot(f.s, normalize(its.dpdu - f.n * dot(f.n, its.dpdu))), 1.0, 1e-12);
    EXPECT_NEAR(its.n.length(), 1.0, 1e-12);
}

Vec3 sphericalPoint(double u, double v) {
    const double theta = kPi * v, phi = 2 * kPi * u;
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

TEST(Differentials, Sphere) {
    for (const bool flip : {false, true}) {
        const Vec3 c(0.3, -1.2, 2.0);
        const double r = 1.7;
        const Transform rot = Transform::rotate(Vec3(1, 2, 3), 40.0);
        Properties p = shapeProps("sphere");
        setPoint(p, "center", c);
        setFloat(p, "radius", r);
        setTransform(p, "toWorld", Transform::translate(c) * rot * Transform::translate(-c));
        setBool(p, "flipNormals", flip);
        auto scene = makeScene({makeShape(p)});
        const Param param = [&](const Vec2 &uv) { return c + rot.vector(sphericalPoint(uv.x, uv.y)) * r; };
        for (const Vec2 &uv : {Vec2(0.1, 0.3), Vec2(0.6, 0.55), Vec2(0.93, 0.8)})
            checkDifferentials(*scene, param, uv, true, flip ? "flipped sphere" : "sphere");
    }
}

TEST(Differentials, Cylinder) {
    for (const bool flip : {false, true}) {
        const Vec3 p0(0.5, -0.5, 1.0), p1(1.5, 1.0, 2.5);
        const double r = 0.4;
        Properties p = shapeProps("cylinder");
        setPoint(p, "p0", p0);
        setPoint(p, "p1", p1);
        setFloat(p, "radius", r);
        setBool(p, "flipNormals", flip);
        auto scene = makeScene({makeShape(p)});
        Vec3 s, t;
        coordinateSystem(normalize(p1 - p0), s, t);
        const Param param = [&](const Vec2 &uv) {
            const double phi = 2 * kPi * uv.x;
            return p0 + (p1 - p0) * uv.y + (s * std::cos(phi) + t * std::sin(phi)) * r;
        };
        for (const Vec2 &uv : {Vec2(0.1, 0.3), Vec2(0.6, 0.55), Vec2(0.93, 0.8)})
            checkDifferentials(*scene, param, uv, true, flip ? "flipped cylinder" : "cylinder");
    }
}

TEST(Differentials, Disk) {
    const Transform m = Transform::translate(Vec3(1, 2, 3)) * Transform::rotate(Vec3(1, 1, 0), 30.0) *
                        Transform::scale(Vec3(2.0, 0.7, 1.0));
    Properties p = shapeProps("disk");
    setTransform(p, "toWorld", m);
    auto scene = makeScene({makeShape(p)});
    const Param param = [&](const Vec2 &uv) {
        const double phi = 2 * kPi * uv.y;
        return m.point(Vec3(uv.x * std::cos(phi), uv.x * std::sin(phi), 0));
    };
    for (const Vec2 &uv : {Vec2(0.3, 0.1), Vec2(0.55, 0.6), Vec2(0.8, 0.93)})
        checkDifferentials(*scene, param, uv, false, "disk");
}

TEST(Differentials, Rectangle) {
    const Transform m = Transform::translate(Vec3(-1, 0, 2)) * Transform::rotate(Vec3(0, 1, 1), 70.0) *
                        Transform::scale(Vec3(3.0, 0.5, 1.0));
    Properties p = shapeProps("rectangle");
    setTransform(p, "toWorld", m);
    auto scene = makeScene({makeShape(p)});
    const Param param = [&](const Vec2 &uv) { return m.point(Vec3(2 * uv.x - 1, 2 * uv.y - 1, 0)); };
    for (const Vec2 &uv : {Vec2(0.3, 0.1), Vec2(0.55, 0.6), Vec2(0.2, 0.93)})
        checkDifferentials(*scene, param, uv, false, "rectangle");
}

TEST(Differentials, CubeFace) {
    const Transform m = Transform::rotate(Vec3(1, 0, 1), 25.0) * Transform::scale(Vec3(1, 2, 3));
    Properties p = shapeProps("cube");
    setTransform(p, "toWorld", m);
    auto scene = makeScene({makeShape(p)});
    // The +x face: corners x = 1, (y, z) = (2u - 1, 2v - 1) in the cube's own coordinates.
    const Param param = [&](const Vec2 &uv) { return m.point(Vec3(1, 2 * uv.x - 1, 2 * uv.y - 1)); };
    for (const Vec2 &uv : {Vec2(0.3, 0.1), Vec2(0.55, 0.6), Vec2(0.2, 0.93)})
        checkDifferentials(*scene, param, uv, false, "cube face");
}

// One triangle with vertex normals that differ strongly, so the shading normal bends across it.
MeshData bentTriangle(bool withUVs, bool withNormals) {
    MeshData d;
    d.positions = {{0, 0, 0}, {2, 0, 0.3}, {0.5, 1.5, -0.2}};
    if (withNormals)
        d.normals = {normalize(Vec3(0.1, 0.2, 1)), normalize(Vec3(-0.6, 0.1, 1)), normalize(Vec3(0.2, -0.5, 1))};
    if (withUVs) d.uvs = {{0.1, 0.2}, {0.9, 0.3}, {0.3, 0.8}};
    d.triangles = {{0, 1, 2}};
    return d;
}

std::shared_ptr<TriangleMesh> makeMesh(MeshData d, const MeshOptions &opts = {}) {
    return std::make_shared<TriangleMesh>(shapeProps("mesh"), std::move(d), opts, "test mesh");
}

// A mesh hit defers dn/du and dn/dv (issue 17): pending after intersection, then filled on request with the
// values the manifold code reads, and ManifoldVertex::surface, the manifold code's entry, completes them itself.
TEST(Differentials, MeshNormalDerivativesOnRequest) {
    auto scene = makeScene({makeMesh(bentTriangle(true, true))});
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(0.8, 0.5, 5), Vec3(0, 0, -1)), its));
    EXPECT_TRUE(its.normalDerivativesPending);
    EXPECT_TRUE(its.dndu.isZero() && its.dndv.isZero());
    const std::optional<ManifoldVertex> v = ManifoldVertex::surface(its, Scattering::Reflection);
    its.shape->fillNormalDerivatives(its);
    EXPECT_FALSE(its.normalDerivativesPending);
    EXPECT_FALSE(its.dndu.isZero());
    EXPECT_FALSE(its.dndv.isZero());
    ASSERT_TRUE(v);
    EXPECT_FALSE(v->its.normalDerivativesPending);
    EXPECT_EQ(v->its.dndu, its.dndu);
    EXPECT_EQ(v->its.dndv, its.dndv);
}

// Flat-shaded meshes (one normal at each triangle's corners) keep a shading frame per triangle (issue 17): a
// hit gets the frame that the general path, interpolating and normalizing the corner normals, computes for the
// same triangle in a mesh that also has a smooth triangle, up to rounding; the geometric normal is turned to
// the shading normal's side in both.
TEST(ShapeHits, FlatShadedMeshFrameIsTheInterpolatedOne) {
    const Vec3 n = normalize(Vec3(0.2, 0.1, -1));  // tilted, and on the side opposite to the winding's normal
    MeshData flat;
    flat.positions = {{0, 0, 0}, {2, 0, 0.3}, {0.5, 1.5, -0.2}};
    flat.normals = {n, n, n};
    flat.triangles = {{0, 1, 2}};
    MeshData mixed = flat;
    const MeshData bent = bentTriangle(false, true);
    for (int k = 0; k < 3; ++k) {
        mixed.positions.push_back(bent.positions[k] + Vec3(10, 0, 0));
        mixed.normals.push_back(bent.normals[k]);
    }
    mixed.triangles.push_back({3, 4, 5});
    auto flatScene = makeScene({makeMesh(flat)}), mixedScene = makeScene({makeMesh(mixed)});
    for (const Vec3 &o : {Vec3(0.8, 0.5, 5), Vec3(0.3, 0.2, -4), Vec3(1.5, 0.1, 3)}) {
        const Ray ray(o, normalize(Vec3(0.7, 0.5, 0.1) - o));
        Intersection a, b;
        ASSERT_TRUE(flatScene->intersect(ray, a));
        ASSERT_TRUE(mixedScene->intersect(ray, b));
        EXPECT_EQ(a.p, b.p);
        EXPECT_EQ(a.n, b.n);
        EXPECT_GT(dot(a.n, n), 0);
        expectVecNear(a.shFrame.n, n, 1e-15, "shading normal");
        expectVecNear(a.shFrame.s, b.shFrame.s, 1e-15, "s");
        expectVecNear(a.shFrame.t, b.shFrame.t, 1e-15, "t");
        expectVecNear(a.shFrame.n, b.shFrame.n, 1e-15, "n");
        EXPECT_NEAR(dot(a.shFrame.s, a.shFrame.n), 0, 1e-15);
        EXPECT_EQ(a.dpdu, b.dpdu);
        EXPECT_EQ(a.dpdv, b.dpdv);
    }
}

TEST(Differentials, Meshes) {
    for (const bool uvs : {true, false})
        for (const bool smooth : {true, false}) {
            MeshData d = bentTriangle(uvs, smooth);
            const MeshData copy = d;
            MeshOptions opts;
            opts.faceNormals = !smooth;
            auto mesh = makeMesh(std::move(d), opts);
            EXPECT_EQ(mesh->hasVertexNormals(), smooth);
            auto scene = makeScene({mesh});
            // p(u, v): barycentrics from the texture mapping (or directly, without one), then the plane.
            const Param param = [&](const Vec2 &uv) {
                double b1 = uv.x, b2 = uv.y;
                if (uvs) {
                    const Vec2 d1 = copy.uvs[1] - copy.uvs[0], d2 = copy.uvs[2] - copy.uvs[0], q = uv - copy.uvs[0];
                    const double det = d1.x * d2.y - d1.y * d2.x;
                    b1 = (q.x * d2.y - q.y * d2.x) / det;
                    b2 = (d1.x * q.y - d1.y * q.x) / det;
                }
                const auto &p = copy.positions;
                return p[0] + (p[1] - p[0]) * b1 + (p[2] - p[0]) * b2;
            };
            const Vec2 pts[2] = {uvs ? Vec2(0.4, 0.4) : Vec2(0.3, 0.3), uvs ? Vec2(0.5, 0.35) : Vec2(0.5, 0.2)};
            const std::string what = std::string(smooth ? "smooth" : "flat") + (uvs ? " mesh with uvs" : " mesh");
            for (const Vec2 &uv : pts) checkDifferentials(*scene, param, uv, false, what.c_str());
            if (!smooth) {
                const Intersection its = hitAt(*scene, param, pts[0]);
                EXPECT_TRUE(its.dndu.isZero() && its.dndv.isZero());
            }
        }
}

// ---------------------------------------------------------------------------------------------------
// Direct sampling against pdfDirect, and area sampling

Chi2Options chi2Options() {
    Chi2Options o;
    o.testCount = kChi2Tests;
    o.integrationRes = 24;  // the densities end at silhouettes; integrate the bins finely
    return o;
}

// Chi-square of the directions that shape->sampleDirect produces from `ref` against pdfDirect, summed over
// every point of the shape along each direction (directions through a closed mesh meet it twice).
void checkDirectSampling(const std::shared_ptr<Shape> &shape, const Vec3 &ref, const char *what) {
    SCOPED_TRACE(what);
    auto scene = makeScene({shape});
    const auto sample = [&](PCG32 &rng, Vec3 &d) {
        DirectSample ds(ref, Vec3());
        const double u1 = rng.nextDouble();
        shape->sampleDirect(ds, Vec2(u1, rng.nextDouble()));
        if (!(ds.pdf > 0)) return false;
        EXPECT_NEAR((ds.p - ref).length(), ds.dist, 1e-9 * (1 + ds.dist));
        d = ds.d;
        return true;
    };
    const auto pdf = [&](const Vec3 &d) {
        double sum = 0;
        Ray ray(ref, d);
        Intersection its;
        while (scene->intersect(ray, its)) {
            DirectSample ds(ref, Vec3());
            ds.p = its.p;
            ds.n = its.n;
            ds.uv = its.uv;
            ds.d = d;
            ds.dist = (its.p - ref).length();
            sum += shape->pdfDirect(ds);
            ray = scene->spawnRay(its, d);
        }
        return sum;
    };
    const Chi2Result r = chi2Sphere(sample, pdf, chi2Options());
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 2e-3) << r.report;
}

TEST(DirectSampling, SphereFromOutside) {
    Properties p = shapeProps("sphere");
    setPoint(p, "center", Vec3(0.5, -0.3, 0.2));
    auto sphere = makeShape(p);
    checkDirectSampling(sphere, Vec3(1.9, 0.6, 0.9), "near");
    checkDirectSampling(sphere, Vec3(-2.5, 1.0, -2.0), "far");
}

TEST(DirectSampling, SphereFromInside) {
    Properties p = shapeProps("sphere");
    setPoint(p, "center", Vec3(0.5, -0.3, 0.2));
    setFloat(p, "radius", 1.5);
    checkDirectSampling(makeShape(p), Vec3(0.9, 0.1, -0.4), "inside");
}

TEST(DirectSampling, MeshLight) {
    Properties p = shapeProps("cube");
    setTransform(p, "toWorld", Transform::rotate(Vec3(1, 1, 0), 30.0) * Transform::scale(Vec3(0.5, 1.0, 1.5)));
    checkDirectSampling(makeShape(p), Vec3(1.5, 1.0, 0.8), "cube");
}

// The solid-angle cone of a sphere seen from outside has the closed-form density 1 / (2 pi (1 - cos)).
TEST(DirectSampling, SphereConeDensity) {
    Properties p = shapeProps("sphere");
    setFloat(p, "radius", 1e-2);
    auto sphere = makeShape(p);
    DirectSample ds(Vec3(0, 0, 100), Vec3());
    sphere->sampleDirect(ds, Vec2(0.3, 0.7));
    const double sin2 = 1e-4 / 1e4, oneMinusCos = sin2 / (1 + std::sqrt(1 - sin2));
    EXPECT_NEAR(ds.pdf * 2 * kPi * oneMinusCos, 1.0, 1e-9);
    EXPECT_NEAR(ds.p.length(), 1e-2, 1e-12);
    EXPECT_GT(ds.p.z, 0.0);  // the near side
    EXPECT_NEAR(sphere->pdfDirect(ds), ds.pdf, 1e-9 * ds.pdf);
}

// Samples positions and checks that each cell of a partition receives its share of the area.
void checkUniform(const std::shared_ptr<Shape> &shape, size_t cells,
                  const std::function<size_t(const PositionSample &)> &cellOf,
                  const std::function<double(size_t)> &cellArea, const char *what) {
    SCOPED_TRACE(what);
    const int n = 100000;
    PCG32 rng(7, 11);
    std::vector<double> observed(cells, 0.0), expected(cells, 0.0);
    for (int i = 0; i < n; ++i) {
        PositionSample ps;
        const double u1 = rng.nextDouble();
        shape->samplePosition(ps, Vec2(u1, rng.nextDouble()));
        ASSERT_NEAR(ps.pdf * shape->surfaceArea(), 1.0, 1e-12);
        ASSERT_EQ(ps.measure, Measure::Area);
        ASSERT_NEAR(ps.n.length(), 1.0, 1e-12);
        observed[cellOf(ps)] += 1;
    }
    double total = 0;
    for (size_t c = 0; c < cells; ++c) total += cellArea(c);
    EXPECT_NEAR(total, shape->surfaceArea(), 1e-9 * total);
    for (size_t c = 0; c < cells; ++c) expected[c] = n * cellArea(c) / total;
    const Chi2Result r = chi2Histogram(observed, expected, 0.01, kChi2Tests);
    EXPECT_TRUE(r.passed) << r.report;
}

TEST(AreaSampling, MeshTrianglesByArea) {
    Properties p = shapeProps("cube");
    setTransform(p, "toWorld", Transform::scale(Vec3(0.5, 1.0, 3.0)));
    auto cube = makeShape(p);
    auto mesh = std::dynamic_pointer_cast<TriangleMesh>(cube);
    ASSERT_TRUE(mesh);
    // Cell = triangle, found by tracing at the sampled point along its normal.
    auto scene = makeScene({cube});
    const auto &pos = mesh->positions();
    const auto &tris = mesh->triangles();
    checkUniform(
        cube, tris.size(),
        [&](const PositionSample &ps) {
            Intersection its;
            EXPECT_TRUE(scene->intersect(Ray(ps.p + ps.n * 0.1, -ps.n), its));
            return static_cast<size_t>(its.primIndex);
        },
        [&](size_t t) {
            return 0.5 * cross(pos[tris[t][1]] - pos[tris[t][0]], pos[tris[t][2]] - pos[tris[t][0]]).length();
        },
        "cube triangles");
}

TEST(AreaSampling, RectangleGrid) {
    const Transform m = Transform::rotate(Vec3(0, 1, 0), 20.0) * Transform::scale(Vec3(2.0, 0.5, 1.0));
    Properties p = shapeProps("rectangle");
    setTransform(p, "toWorld", m);
    const int g = 8;
    checkUniform(
        makeShape(p), g * g,
        [&](const PositionSample &ps) {
            const Vec3 l = m.inverse().point(ps.p);
            const int i = std::min(g - 1, static_cast<int>((l.x + 1) * 0.5 * g));
            const int j = std::min(g - 1, static_cast<int>((l.y + 1) * 0.5 * g));
            return static_cast<size_t>(j * g + i);
        },
        [&](size_t) { return 4.0 / (g * g); }, "rectangle grid");
}

// A rectangle samples positions as Mitsuba 0.6 samples its analytic rectangle: u = (x, y) goes to toWorld(2x - 1,
// 2y - 1, 0), with uv = u (TriangleMesh's parallelogram sampling).
TEST(AreaSampling, RectangleMapsTheSquareAffinely) {
    const Transform m = Transform::translate(Vec3(0.3, -2, 1)) * Transform::rotate(Vec3(1, 0, 0), 30.0) *
                        Transform::scale(Vec3(2.0, 0.5, 1.0));
    Properties p = shapeProps("rectangle");
    setTransform(p, "toWorld", m);
    const auto rect = makeShape(p);
    for (const Vec2 u : {Vec2(0.1, 0.2), Vec2(0.7, 0.3), Vec2(0.5, 0.5), Vec2(0.0, 0.999), Vec2(0.999, 0.0)}) {
        PositionSample ps;
        rect->samplePosition(ps, u);
        expectVecNear(ps.p, m.point(Vec3(2 * u.x - 1, 2 * u.y - 1, 0)), 1e-12, "p");
        EXPECT_NEAR(ps.uv.x, u.x, 1e-12);
        EXPECT_NEAR(ps.uv.y, u.y, 1e-12);
        EXPECT_NEAR(ps.pdf, 0.25, 1e-12);  // the square's area 4, scaled by 2 * 0.5
    }
}

// A quad read from a mesh file, a sheared parallelogram whose triangles share the other diagonal than a
// rectangle's and are wound the other way: uniform over a grid in its own edge coordinates.
TEST(AreaSampling, ParallelogramMeshGrid) {
    MeshData d;
    const Vec3 P(0.5, 0, 0), e1(2, 0.2, 0.5), e2(0.7, 1.5, -0.3);
    d.positions = {P, P + e1, P + e1 + e2, P + e2};
    d.triangles = {{0, 3, 1}, {1, 3, 2}};  // diagonal 1 - 3
    const auto mesh = makeMesh(d);
    const int g = 6;
    const double e11 = dot(e1, e1), e12 = dot(e1, e2), e22 = dot(e2, e2), det = e11 * e22 - e12 * e12;
    checkUniform(
        mesh, g * g,
        [&](const PositionSample &ps) {
            const Vec3 r = ps.p - P;
            const double a = (e22 * dot(e1, r) - e12 * dot(e2, r)) / det,
                         b = (e11 * dot(e2, r) - e12 * dot(e1, r)) / det;
            EXPECT_NEAR(dot(r - e1 * a - e2 * b, r - e1 * a - e2 * b), 0.0, 1e-20);
            const int i = std::clamp(static_cast<int>(a * g), 0, g - 1),
                      j = std::clamp(static_cast<int>(b * g), 0, g - 1);
            return static_cast<size_t>(j * g + i);
        },
        [&](size_t) { return cross(e1, e2).length() / (g * g); }, "parallelogram grid");
}

// Two triangles that form no parallelogram (a trapezoid, areas 1.5 and 1) are still chosen by area.
TEST(AreaSampling, TrapezoidTrianglesByArea) {
    MeshData d;
    d.positions = {{0, 0, 0}, {3, 0, 0}, {2, 1, 0}, {0, 1, 0}};
    d.triangles = {{0, 1, 2}, {0, 2, 3}};
    checkUniform(
        makeMesh(d), 2, [](const PositionSample &ps) { return static_cast<size_t>(ps.p.y > 0.5 * ps.p.x ? 1 : 0); },
        [](size_t t) { return t == 0 ? 1.5 : 1.0; }, "trapezoid triangles");
}

TEST(AreaSampling, DiskRingsAndSectors) {
    const Transform m = Transform::scale(Vec3(1.5, 0.5, 1.0));
    Properties p = shapeProps("disk");
    setTransform(p, "toWorld", m);
    const int rings = 4, sectors = 8;
    checkUniform(
        makeShape(p), rings * sectors,
        [&](const PositionSample &ps) {
            const Vec3 l = m.inverse().point(ps.p);
            const int ring = std::min(rings - 1, static_cast<int>((l.x * l.x + l.y * l.y) * rings));
            double phi = std::atan2(l.y, l.x);
            if (phi < 0) phi += 2 * kPi;
            const int sector = std::min(sectors - 1, static_cast<int>(phi / (2 * kPi) * sectors));
            return static_cast<size_t>(ring * sectors + sector);
        },
        [&](size_t) { return kPi * 0.75 / (rings * sectors); }, "disk");
}

TEST(AreaSampling, CylinderGrid) {
    Properties p = shapeProps("cylinder");
    setPoint(p, "p1", Vec3(0, 0, 3));
    setFloat(p, "radius", 0.5);
    const int g = 8;
    checkUniform(
        makeShape(p), g * g,
        [&](const PositionSample &ps) {
            double phi = std::atan2(ps.p.y, ps.p.x);
            if (phi < 0) phi += 2 * kPi;
            const int i = std::min(g - 1, static_cast<int>(phi / (2 * kPi) * g));
            const int j = std::min(g - 1, static_cast<int>(ps.p.z / 3.0 * g));
            return static_cast<size_t>(j * g + i);
        },
        [&](size_t) { return 2 * kPi * 0.5 * 3.0 / (g * g); }, "cylinder");
}

TEST(AreaSampling, Sphere) {
    Properties p = shapeProps("sphere");
    setPoint(p, "center", Vec3(1, 2, 3));
    setFloat(p, "radius", 0.5);
    auto sphere = makeShape(p);
    const auto sample = [&](PCG32 &rng, Vec3 &d) {
        PositionSample ps;
        const double u1 = rng.nextDouble();
        sphere->samplePosition(ps, Vec2(u1, rng.nextDouble()));
        d = (ps.p - Vec3(1, 2, 3)) / 0.5;
        EXPECT_NEAR(dot(d, ps.n), 1.0, 1e-12);
        return true;
    };
    const Chi2Result r = chi2Sphere(
        sample, [](const Vec3 &) { return kInvFourPi; }, chi2Options());
    EXPECT_TRUE(r.passed) << r.report;
}

// ---------------------------------------------------------------------------------------------------
// Mesh files

std::shared_ptr<Shape> loadMesh(const std::string &plugin, const std::string &dir, const std::string &file,
                                const std::function<void(Properties &)> &extra = {}) {
    Properties p = shapeProps(plugin);
    setString(p, "filename", file);
    if (extra) extra(p);
    return makeShape(p, LoadContext{dir, dir});
}

std::shared_ptr<TriangleMesh> asMesh(const std::shared_ptr<Shape> &s) {
    auto m = std::dynamic_pointer_cast<TriangleMesh>(s);
    EXPECT_TRUE(m);
    return m;
}

const char *kQuadObj =
    "# a unit quad\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "vn 0 0 1\n"
    "mtllib quad.mtl\ng quad\nusemtl none\n"
    "f 1/1/1 2/2/1 3/3/1 4/4/1\n";

TEST(MeshFiles, ObjQuadWithTexCoordsAndNormals) {
    const std::string dir = tempDir("shapes-obj-quad");
    writeFile(dir, "quad.obj", kQuadObj);
    for (const bool flip : {true, false}) {
        auto mesh = asMesh(loadMesh("obj", dir, "quad.obj", [&](Properties &p) {
            if (!flip) setBool(p, "flipTexCoords", false);
        }));
        EXPECT_EQ(mesh->vertexCount(), 4u);
        EXPECT_EQ(mesh->primitiveCount(), 2u);
        ASSERT_TRUE(mesh->hasVertexNormals());
        for (const Vec3 &n : mesh->normals()) expectVecNear(n, Vec3(0, 0, 1), 1e-12, "normal");
        auto scene = makeScene({mesh});
        Intersection its;
        ASSERT_TRUE(scene->intersect(Ray(Vec3(0.25, 0.75, 1), Vec3(0, 0, -1)), its));
        // Mitsuba flips v by default.
        EXPECT_NEAR(its.uv.x, 0.25, 1e-12);
        EXPECT_NEAR(its.uv.y, flip ? 0.25 : 0.75, 1e-12);
    }
}

// A tetrahedron with relative (negative) indices and no normals: smooth, angle-weighted normals are
// generated, unless faceNormals is set.
TEST(MeshFiles, ObjGeneratedNormals) {
    const std::string dir = tempDir("shapes-obj-tet");
    writeFile(dir, "tet.obj",
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
              "f -4 -2 -3\nf -4 -3 -1\nf -4 -1 -2\nf -3 -2 -1\n");
    auto mesh = asMesh(loadMesh("obj", dir, "tet.obj"));
    EXPECT_EQ(mesh->vertexCount(), 4u);
    EXPECT_EQ(mesh->primitiveCount(), 4u);
    ASSERT_TRUE(mesh->hasVertexNormals());
    for (size_t i = 0; i < mesh->vertexCount(); ++i) {
        const Vec3 &p = mesh->positions()[i], &n = mesh->normals()[i];
        if (p == Vec3(0, 0, 0)) expectVecNear(n, normalize(Vec3(-1, -1, -1)), 1e-12, "corner normal");
        if (p == Vec3(1, 0, 0)) {
            // Faces -z and -y meet there at 45 degrees, the slanted face (1,1,1)/sqrt(3) at 60 degrees.
            const Vec3 expect =
                Vec3(0, 0, -1) * (kPi / 4) + Vec3(0, -1, 0) * (kPi / 4) + normalize(Vec3(1, 1, 1)) * (kPi / 3);
            expectVecNear(n, normalize(expect), 1e-12, "angle-weighted normal");
        }
    }
    auto faceted = asMesh(loadMesh("obj", dir, "tet.obj", [](Properties &p) { setBool(p, "faceNormals", true); }));
    EXPECT_FALSE(faceted->hasVertexNormals());
    auto flipped = asMesh(loadMesh("obj", dir, "tet.obj", [](Properties &p) { setBool(p, "flipNormals", true); }));
    for (size_t i = 0; i < flipped->vertexCount(); ++i)
        expectVecNear(flipped->normals()[i], -mesh->normals()[i], 1e-12, "flipped normal");
}

TEST(MeshFiles, ObjMaxSmoothAngle) {
    const std::string dir = tempDir("shapes-obj-cube");
    writeFile(dir, "cube.obj",
              "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
              "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
    auto smooth = asMesh(loadMesh("obj", dir, "cube.obj"));
    EXPECT_EQ(smooth->vertexCount(), 8u);
    EXPECT_EQ(smooth->primitiveCount(), 12u);
    auto creased = asMesh(loadMesh("obj", dir, "cube.obj", [](Properties &p) { setFloat(p, "maxSmoothAngle", 30.0); }));
    EXPECT_EQ(creased->vertexCount(), 24u);
    for (size_t i = 0; i < creased->vertexCount(); ++i) {
        const Vec3 &n = creased->normals()[i];
        EXPECT_NEAR(std::abs(n.x) + std::abs(n.y) + std::abs(n.z), 1.0, 1e-12) << "axis-aligned normal " << n;
    }
    auto rounded =
        asMesh(loadMesh("obj", dir, "cube.obj", [](Properties &p) { setFloat(p, "maxSmoothAngle", 100.0); }));
    EXPECT_EQ(rounded->vertexCount(), 8u);
}

TEST(MeshFiles, PlyAscii) {
    const std::string dir = tempDir("shapes-ply-ascii");
    writeFile(dir, "quad.ply",
              "ply\nformat ascii 1.0\ncomment a quad\n"
              "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\nproperty float s\nproperty float t\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
              "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n4 0 1 2 3\n");
    auto mesh = asMesh(loadMesh("ply", dir, "quad.ply"));
    EXPECT_EQ(mesh->vertexCount(), 4u);
    EXPECT_EQ(mesh->primitiveCount(), 2u);
    EXPECT_TRUE(mesh->hasVertexNormals());
    EXPECT_TRUE(mesh->hasTexCoords());
    auto scene = makeScene({mesh});
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(0.25, 0.75, 1), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.uv.x, 0.25, 1e-12);
    EXPECT_NEAR(its.uv.y, 0.75, 1e-12);
}

template <typename T>
void putValue(std::string &out, T v, bool bigEndian) {
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    if (bigEndian) std::reverse(b, b + sizeof(T));
    out.append(b, sizeof(T));
}

// A pentagon (a fan of 3 triangles) with an unused colour per vertex and an extra element after the faces.
std::string binaryPly(bool bigEndian) {
    std::string s = std::string("ply\nformat ") + (bigEndian ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 5\nproperty double x\nproperty float y\nproperty float z\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                    "element face 1\nproperty list uchar uint vertex_index\n"
                    "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n";
    for (int i = 0; i < 5; ++i) {
        const double a = 2 * kPi * i / 5;
        putValue<double>(s, std::cos(a), bigEndian);
        putValue<float>(s, static_cast<float>(std::sin(a)), bigEndian);
        putValue<float>(s, 0.0f, bigEndian);
        for (int c = 0; c < 3; ++c) putValue<uint8_t>(s, 200, bigEndian);
    }
    putValue<uint8_t>(s, 5, bigEndian);
    for (uint32_t i = 0; i < 5; ++i) putValue<uint32_t>(s, i, bigEndian);
    putValue<int32_t>(s, 0, bigEndian);
    putValue<int32_t>(s, 1, bigEndian);
    return s;
}

TEST(MeshFiles, PlyBinaryBothByteOrders) {
    const std::string dir = tempDir("shapes-ply-binary");
    for (const bool big : {false, true}) {
        writeFile(dir, "pentagon.ply", binaryPly(big));
        auto mesh = asMesh(loadMesh("ply", dir, "pentagon.ply"));
        EXPECT_EQ(mesh->vertexCount(), 5u);
        EXPECT_EQ(mesh->primitiveCount(), 3u);
        EXPECT_NEAR(mesh->positions()[1].x, std::cos(2 * kPi / 5), 1e-15);
        EXPECT_NEAR(mesh->positions()[1].y, std::sin(2 * kPi / 5), 1e-7);
        EXPECT_NEAR(mesh->surfaceArea(), 2.5 * std::sin(2 * kPi / 5), 1e-6);
        for (const Vec3 &n : mesh->normals()) expectVecNear(n, Vec3(0, 0, 1), 1e-12, "generated normal");
    }
}

struct SerializedShape {
    uint32_t flags = 0;
    std::vector<Vec3> positions, normals;
    std::vector<Vec2> uvs;
    std::vector<std::array<uint32_t, 3>> triangles;
};

// Writes one mesh as Mitsuba does: header, then the zlib-compressed record.
std::string serializedRecord(const SerializedShape &m, uint16_t version) {
    const bool dbl = m.flags & 0x2000;
    std::string body;
    putValue<uint32_t>(body, m.flags, false);
    if (version == 4) body += std::string("mesh") + '\0';
    putValue<uint64_t>(body, m.positions.size(), false);
    putValue<uint64_t>(body, m.triangles.size(), false);
    const auto real = [&](double v) {
        if (dbl)
            putValue<double>(body, v, false);
        else
            putValue<float>(body, static_cast<float>(v), false);
    };
    for (const std::vector<Vec3> *vs : {&m.positions, &m.normals})
        for (const Vec3 &v : *vs)
            for (int k = 0; k < 3; ++k) real(v[k]);
    for (const Vec2 &uv : m.uvs) {
        real(uv.x);
        real(uv.y);
    }
    if (m.flags & 0x0008)
        for (size_t i = 0; i < 3 * m.positions.size(); ++i) real(0.5);
    for (const auto &t : m.triangles)
        for (uint32_t i : t) putValue<uint32_t>(body, i, false);
    uLongf size = compressBound(body.size());
    std::string packed(size, '\0');
    EXPECT_EQ(compress2(reinterpret_cast<Bytef *>(packed.data()), &size, reinterpret_cast<const Bytef *>(body.data()),
                        body.size(), 9),
              Z_OK);
    packed.resize(size);
    std::string out;
    putValue<uint16_t>(out, 0x041C, false);
    putValue<uint16_t>(out, version, false);
    return out + packed;
}

std::string serializedFile(const std::vector<SerializedShape> &meshes, uint16_t version) {
    std::string file;
    std::vector<uint64_t> offsets;
    for (const auto &m : meshes) {
        offsets.push_back(file.size());
        file += serializedRecord(m, version);
    }
    for (uint64_t o : offsets) {
        if (version == 4)
            putValue<uint64_t>(file, o, false);
        else
            putValue<uint32_t>(file, static_cast<uint32_t>(o), false);
    }
    putValue<uint32_t>(file, static_cast<uint32_t>(meshes.size()), false);
    return file;
}

SerializedShape serializedTriangle() {
    SerializedShape m;
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    m.triangles = {{0, 1, 2}};
    return m;
}

SerializedShape serializedQuad() {
    SerializedShape m;
    m.flags = 0x0001 | 0x0002 | 0x0008 | 0x2000;  // normals, uvs, colours, double precision
    m.positions = {{0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}};
    m.normals.assign(4, Vec3(0, 0, -1));
    m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    m.triangles = {{0, 2, 1}, {0, 3, 2}};
    return m;
}

TEST(MeshFiles, SerializedVersions) {
    const std::string dir = tempDir("shapes-serialized");
    for (const uint16_t version : {3, 4}) {
        writeFile(dir, "two.serialized", serializedFile({serializedTriangle(), serializedQuad()}, version));
        auto first = asMesh(loadMesh("serialized", dir, "two.serialized"));
        EXPECT_EQ(first->vertexCount(), 3u);
        EXPECT_EQ(first->primitiveCount(), 1u);
        EXPECT_NEAR(first->surfaceArea(), 0.5, 1e-12);
        auto second =
            asMesh(loadMesh("serialized", dir, "two.serialized", [](Properties &p) { setInt(p, "shapeIndex", 1); }));
        EXPECT_EQ(second->vertexCount(), 4u);
        EXPECT_EQ(second->primitiveCount(), 2u);
        EXPECT_TRUE(second->hasTexCoords());
        ASSERT_TRUE(second->hasVertexNormals());
        expectVecNear(second->normals()[2], Vec3(0, 0, -1), 1e-15, "stored normal");
        expectVecNear(second->positions()[2], Vec3(2, 2, 1), 1e-15, "double-precision position");
        // The face-normals flag of the file gives a faceted mesh.
        SerializedShape faceted = serializedTriangle();
        faceted.flags = 0x0010;
        writeFile(dir, "faceted.serialized", serializedFile({faceted}, version));
        EXPECT_FALSE(asMesh(loadMesh("serialized", dir, "faceted.serialized"))->hasVertexNormals());
    }
}

// ---------------------------------------------------------------------------------------------------
// Corrupt mesh files: a SceneError naming the file, and the line where the format has lines

void expectMeshError(const std::function<void()> &load, const std::string &path, int line, const std::string &what) {
    try {
        load();
        ADD_FAILURE() << "no error for " << what;
    } catch (const SceneError &e) {
        EXPECT_EQ(e.location().file, path) << what << ": " << e.what();
        if (line > 0) {
            EXPECT_EQ(e.location().line, line) << what << ": " << e.what();
        }
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
}

TEST(CorruptMeshes, Obj) {
    const std::string dir = tempDir("shapes-bad-obj");
    const std::string header = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const std::pair<std::string, int> cases[] = {
        {header + "v nan 0 0\nf 1 2 3\n", 4},
        {header + "v 1 2\nf 1 2 3\n", 4},
        {header + "f 1 2 4\n", 4},
        {header + "f 1 2 -4\n", 4},
        {header + "f 1 2\n", 4},
        {header + "f 1/7 2 3\n", 4},
        {header + "vn 0 0 1\nf 1//2 2//1 3//1\n", 5},
        {header + "v 1e999 0 0\nf 1 2 3\n", 4},
        {header + "f 1 2 x\n", 4},
    };
    for (size_t i = 0; i < std::size(cases); ++i) {
        const std::string path = writeFile(dir, "bad" + std::to_string(i) + ".obj", cases[i].first);
        expectMeshError([&] { readOBJ(path, true); }, path, cases[i].second, cases[i].first);
    }
    // Whole-mesh problems name the file: no faces; only degenerate faces.
    for (const std::string &text : {header, header + "v 2 0 0\nf 1 2 4\n"}) {
        const std::string path = writeFile(dir, "empty.obj", text);
        expectMeshError([&] { loadMesh("obj", dir, "empty.obj"); }, path, 0, text);
    }
    expectMeshError([&] { readOBJ(dir + "/missing.obj", true); }, dir + "/missing.obj", 0, "missing file");
}

TEST(CorruptMeshes, Ply) {
    const std::string dir = tempDir("shapes-bad-ply");
    const std::string head =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const std::pair<std::string, int> cases[] = {
        {head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", 13},
        {head + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", 11},
        {head + "0 0 0\n1 0 0\n0 1 0\n2 0 1\n", 13},
        {head + "0 0 0\n1 0 0\n0 1 0\n3 0 1\n", 0},  // ends early
        {head + "0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n", 11},
        {head + "0 0 0\n1 0 0\n0 1 0\n3 0 1 1.5\n", 13},
        {"plx\n" + head.substr(4), 1},
        {"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n", 4},  // no end_header
        {"ply\nformat text 1.0\n", 2},
        {"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", 3},
        {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", 3},
    };
    for (size_t i = 0; i < std::size(cases); ++i) {
        const std::string path = writeFile(dir, "bad" + std::to_string(i) + ".ply", cases[i].first);
        expectMeshError([&] { readPLY(path); }, path, cases[i].second, cases[i].first);
    }
    // Truncated binary data, and a face element without faces.
    std::string truncated = binaryPly(false);
    truncated.resize(truncated.size() - 12);
    const std::string tpath = writeFile(dir, "truncated.ply", truncated);
    expectMeshError([&] { readPLY(tpath); }, tpath, 0, "truncated binary");
    const std::string epath = writeFile(dir, "nofaces.ply",
                                        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float "
                                        "y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n");
    expectMeshError([&] { loadMesh("ply", dir, "nofaces.ply"); }, epath, 0, "no faces");
}

TEST(CorruptMeshes, Serialized) {
    const std::string dir = tempDir("shapes-bad-serialized");
    const std::string good = serializedFile({serializedTriangle(), serializedQuad()}, 4);
    std::string badId = good, badVersion = good, truncated = good.substr(0, 30), garbage = good;
    badId[0] = 0x1D;
    badVersion[2] = 5;
    for (size_t i = 8; i < 40; ++i) garbage[i] = static_cast<char>(i * 37);
    const std::pair<std::string, std::string> cases[] = {
        {"id.serialized", badId},
        {"version.serialized", badVersion},
        {"truncated.serialized", truncated},
        {"garbage.serialized", garbage},
        {"tiny.serialized", std::string("\x1C\x04", 2)},
    };
    for (const auto &[name, bytes] : cases) {
        const std::string path = writeFile(dir, name, bytes);
        expectMeshError([&] { readSerialized(path, 0); }, path, 0, name);
    }
    const std::string path = writeFile(dir, "good.serialized", good);
    expectMeshError([&] { readSerialized(path, 2); }, path, 0, "shapeIndex out of range");
    // A record whose zlib stream lacks its last bytes (the checksum and the end of the data).
    const std::string record = serializedRecord(serializedQuad(), 4);
    const std::string cpath = writeFile(dir, "cut.serialized", record.substr(0, record.size() - 6));
    expectMeshError([&] { readSerialized(cpath, 0); }, cpath, 0, "cut stream");
}

TEST(CorruptMeshes, NonFiniteAndOutOfRangeData) {
    MeshData d = bentTriangle(true, true);
    d.triangles.push_back({0, 1, 7});
    EXPECT_THROW(makeMesh(d), SceneError);
    d = bentTriangle(true, true);
    d.normals[1] = Vec3(0, 0, 0);
    EXPECT_THROW(makeMesh(d), SceneError);
    d = bentTriangle(true, true);
    d.uvs[2].x = std::nan("");
    EXPECT_THROW(makeMesh(d), SceneError);
    // A degenerate triangle next to a good one is dropped.
    d = bentTriangle(false, false);
    d.positions.push_back(d.positions[1] * 2.0);
    d.triangles.push_back({0, 1, 3});
    EXPECT_EQ(makeMesh(d)->primitiveCount(), 1u);
}

// ---------------------------------------------------------------------------------------------------
// Instancing

TEST(Instancing, InstancesRenderTransformedGroupShapes) {
    Properties sphere = shapeProps("sphere");
    setFloat(sphere, "radius", 0.5);
    Properties rect = shapeProps("rectangle");
    setTransform(rect, "toWorld", Transform::translate(Vec3(0, 0, -1)));
    Properties group = shapeProps("shapegroup");
    group.addChild({"", ObjectKind::Shape, makeShape(sphere), kLoc});
    group.addChild({"", ObjectKind::Shape, makeShape(rect), kLoc});
    auto g = makeShape(group);

    Properties a = shapeProps("instance"), b = shapeProps("instance");
    setTransform(a, "toWorld", Transform::translate(Vec3(5, 0, 0)));
    const Transform tb =
        Transform::translate(Vec3(-5, 0, 0)) * Transform::rotate(Vec3(0, 1, 0), 90.0) * Transform::scale(Vec3(2.0));
    setTransform(b, "toWorld", tb);
    a.addChild({"", ObjectKind::Shape, g, kLoc});
    b.addChild({"", ObjectKind::Shape, g, kLoc});
    auto scene = makeScene({g, makeShape(a), makeShape(b)});
    EXPECT_EQ(scene->shapes().size(), 4u);

    Intersection its;
    // The group itself is not rendered.
    EXPECT_FALSE(scene->intersect(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)), its));
    // Instance a: the sphere at x = 5, the rectangle below it.
    ASSERT_TRUE(scene->intersect(Ray(Vec3(5, 0, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 4.5, 1e-12);
    ASSERT_TRUE(scene->intersect(Ray(Vec3(5.8, 0, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 6.0, 1e-12);
    expectVecNear(its.n, Vec3(0, 0, 1), 1e-12, "rectangle normal");
    // Instance b: scaled by 2 and turned a quarter about y, so that the rectangle stands upright 2 units to
    // the side of the centre, and the sphere has radius 1.
    ASSERT_TRUE(scene->intersect(Ray(Vec3(-5, 0, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 4.0, 1e-12);
    const Vec3 rectCentre = tb.point(Vec3(0, 0, -1)), rectNormal = normalize(tb.normal(Vec3(0, 0, 1)));
    EXPECT_NEAR(std::abs(rectNormal.x), 1.0, 1e-12);
    ASSERT_TRUE(scene->intersect(Ray(Vec3(rectCentre.x - 3 * rectNormal.x, 1.5, 0.5), rectNormal), its));
    EXPECT_NEAR(its.t, 3.0, 1e-12);
    expectVecNear(its.n, rectNormal, 1e-12, "rotated rectangle normal");
    EXPECT_NEAR(scene->shapes()[2]->surfaceArea(), 4 * kPi, 1e-12);

    // A sphere cannot be scaled non-uniformly, and groups cannot nest.
    Properties c = shapeProps("instance");
    setTransform(c, "toWorld", Transform::scale(Vec3(1, 2, 1)));
    c.addChild({"", ObjectKind::Shape, g, kLoc});
    EXPECT_THROW(makeShape(c), SceneError);
    Properties nested = shapeProps("shapegroup");
    nested.addChild({"", ObjectKind::Shape, g, kLoc});
    EXPECT_THROW(makeShape(nested), SceneError);
}

// ---------------------------------------------------------------------------------------------------
// BSDFs and emitters attached to shapes

TEST(ShapeChildren, DefaultBSDFAndEmitter) {
    auto plain = makeShape(shapeProps("sphere"));
    ASSERT_NE(plain->bsdf(), nullptr);
    EXPECT_FALSE(plain->bsdf()->isNull());
    EXPECT_NE(plain->bsdf()->flags() & BSDFFlags::DiffuseReflection, 0u);

    Properties e(ObjectKind::Emitter, "area", kLoc);
    auto emitter = std::dynamic_pointer_cast<Emitter>((*findPlugin(ObjectKind::Emitter, "area"))(e, {}));
    Properties lit = shapeProps("disk");
    lit.addChild({"", ObjectKind::Emitter, emitter, kLoc});
    auto light = makeShape(lit);
    EXPECT_EQ(light->emitter(), emitter.get());
    EXPECT_EQ(emitter->shape(), light.get());
    ASSERT_NE(light->bsdf(), nullptr);
    Intersection its;
    its.shape = light.get();
    // Mitsuba gives emitters without a BSDF a black diffuse one.
    EXPECT_TRUE(light->bsdf()->diffuseReflectance(its).isBlack());
    // The same emitter cannot light a second shape.
    Properties again = shapeProps("disk");
    again.addChild({"", ObjectKind::Emitter, emitter, kLoc});
    EXPECT_THROW(makeShape(again), SceneError);
}

TEST(ShapeChildren, BadParameters) {
    const auto expectFail = [](Properties p, const std::string &param) {
        try {
            makeShape(p);
            ADD_FAILURE() << "no error for " << param;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("'" + param + "'"), std::string::npos) << e.what();
        }
    };
    Properties r = shapeProps("sphere");
    setFloat(r, "radius", -1.0);
    expectFail(r, "radius");
    Properties s = shapeProps("sphere");
    setTransform(s, "toWorld", Transform::scale(Vec3(1, 1, 3)));
    expectFail(s, "toWorld");
    Properties c = shapeProps("cylinder");
    setPoint(c, "p1", Vec3(0, 0, 0));
    expectFail(c, "p1");
    Properties e = shapeProps("cylinder");
    setTransform(e, "toWorld", Transform::scale(Vec3(2, 1, 1)));
    expectFail(e, "toWorld");
    // A flat matrix (the loader refuses singular transforms; the disk checks anyway).
    Matrix4 flat = Matrix4::identity();
    flat.m[1][1] = 0;
    Properties d = shapeProps("disk");
    setTransform(d, "toWorld", Transform(flat, Matrix4::identity()));
    expectFail(d, "toWorld");
}

}  // namespace
}  // namespace pf::test
