// The Scene: ray offsetting (no self-intersection far from the origin, no leaks through thin geometry
// near it), shadow rays, the per-thread ray counter and ray recording, finalize's checks, bounds, and
// emitter selection with the selection probability folded into direct sampling.
#include <gtest/gtest.h>

#include <thread>

#include "core/rng.h"
#include "core/warp.h"
#include "emitter/emitter.h"
#include "scene/plugins.h"
#include "scene/scene.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

const SourceLocation kLoc{"test.xml", 1};

Properties shapeProps(const std::string &plugin) { return Properties(ObjectKind::Shape, plugin, kLoc); }
void setTransform(Properties &p, const Transform &t) { p.set("toWorld", Properties::Type::Transform, t, kLoc); }
void setPoint(Properties &p, const std::string &n, const Vec3 &v) { p.set(n, Properties::Type::Point, v, kLoc); }
void setFloat(Properties &p, const std::string &n, double v) { p.set(n, Properties::Type::Float, v, kLoc); }

std::shared_ptr<Shape> makeShape(const Properties &p) {
    return std::dynamic_pointer_cast<Shape>((*findPlugin(ObjectKind::Shape, p.pluginName()))(p, LoadContext{}));
}

std::shared_ptr<Sensor> makeSensor() {
    const Properties p(ObjectKind::Sensor, "perspective", kLoc);
    return std::dynamic_pointer_cast<Sensor>((*findPlugin(ObjectKind::Sensor, "perspective"))(p, {}));
}

std::shared_ptr<Emitter> makeEmitter(const std::string &type, double weight) {
    Properties p(ObjectKind::Emitter, type, kLoc);
    p.set("samplingWeight", Properties::Type::Float, weight, kLoc);
    return std::dynamic_pointer_cast<Emitter>((*findPlugin(ObjectKind::Emitter, type))(p, {}));
}

std::unique_ptr<Scene> makeScene(const std::vector<std::shared_ptr<Shape>> &shapes) {
    auto scene = std::make_unique<Scene>();
    for (const auto &s : shapes) scene->addShape(s);
    scene->setSensor(makeSensor());
    scene->finalize();
    return scene;
}

// A direction in the hemisphere around n (uniform).
Vec3 hemisphere(const Vec3 &n, PCG32 &rng) {
    const double u1 = rng.nextDouble();
    return Frame(n).toWorld(warp::squareToUniformHemisphere(Vec2(u1, rng.nextDouble())));
}

// Convex shapes far from the origin. A ray leaving a convex solid's surface outwards cannot meet the
// solid again; one going inwards meets it next where it leaves, through surface whose outward normal
// points along the ray. A self-intersection at the launch point breaks one of the two.
TEST(RayOffset, NoSelfIntersectionFarFromOrigin) {
    const Vec3 c(1000, -1200, 900);
    Properties sphere = shapeProps("sphere");
    setPoint(sphere, "center", c);
    Properties cube = shapeProps("cube");
    setTransform(cube, Transform::translate(c + Vec3(5, 0, 0)) * Transform::rotate(Vec3(1, 2, 3), 20.0));
    Properties cyl = shapeProps("cylinder");
    setPoint(cyl, "p0", c + Vec3(-5, 0, -1));
    setPoint(cyl, "p1", c + Vec3(-5, 0, 1));
    auto scene = makeScene({makeShape(sphere), makeShape(cube), makeShape(cyl)});
    const Shape *openCylinder = scene->shapes()[2].get();

    PCG32 rng(3, 5);
    int selfHits = 0, wrongExits = 0, leaks = 0, tested = 0;
    for (int i = 0; i < 30000; ++i) {
        const Vec3 centre = c + Vec3((i % 3 - 1) * 5.0, 0, 0);
        const Vec3 aim = centre + Vec3(rng.nextDouble() - 0.5, rng.nextDouble() - 0.5, rng.nextDouble() - 0.5) * 1.6;
        const Vec3 dir = normalize(Vec3(rng.nextDouble() - 0.5, rng.nextDouble() - 0.5, rng.nextDouble() - 0.5));
        Intersection its, next;
        if (!scene->intersect(Ray(aim - dir * 20.0, dir), its)) continue;
        ++tested;
        // its.n is the outward normal of these shapes (also on the inner wall of the cylinder).
        if (scene->intersect(scene->spawnRay(its, hemisphere(its.n, rng)), next) && next.shape == its.shape) ++selfHits;
        const Vec3 in = hemisphere(-its.n, rng);
        if (!scene->intersect(scene->spawnRay(its, in), next)) {
            if (its.shape != openCylinder) ++leaks;  // only the open cylinder can be left without a hit
        } else if (next.shape == its.shape && dot(next.n, in) <= 0) {
            ++wrongExits;
        }
    }
    EXPECT_GT(tested, 15000);
    EXPECT_EQ(selfHits, 0);
    EXPECT_EQ(wrongExits, 0);
    EXPECT_EQ(leaks, 0);
}

// At coordinates ~1e3 a ray entering a closed mesh meets exactly one more surface (the exit), and nothing
// after it.
TEST(RayOffset, ClosedMeshFarFromOriginIsCrossedExactly) {
    const Vec3 c(1500, 800, -1100);
    Properties cube = shapeProps("cube");
    setTransform(cube, Transform::translate(c) * Transform::rotate(Vec3(0, 1, 1), 33.0));
    auto scene = makeScene({makeShape(cube)});
    PCG32 rng(9, 1);
    int bad = 0;
    for (int i = 0; i < 20000; ++i) {
        const Vec3 aim = c + Vec3(rng.nextDouble() - 0.5, rng.nextDouble() - 0.5, rng.nextDouble() - 0.5);
        const Vec3 dir = normalize(Vec3(rng.nextDouble() - 0.5, rng.nextDouble() - 0.5, rng.nextDouble() - 0.5));
        Intersection its, next, after;
        ASSERT_TRUE(scene->intersect(Ray(aim - dir * 10.0, dir), its));
        const Vec3 in = hemisphere(-its.n, rng);
        if (!scene->intersect(scene->spawnRay(its, in), next) || dot(next.n, in) <= 0) {
            ++bad;
            continue;
        }
        if (scene->intersect(scene->spawnRay(next, in), after)) ++bad;
        if (scene->intersect(scene->spawnRay(next, hemisphere(next.n, rng)), after)) ++bad;
    }
    EXPECT_EQ(bad, 0);
}

// A slab 1e-3 thick near the origin (two rectangles facing apart, and a flattened cube): rays entering
// from the top must stop at the bottom, never leak through.
TEST(RayOffset, NoLeakThroughThinGeometryNearOrigin) {
    const double thickness = 1e-3;
    Properties top = shapeProps("rectangle"), bottom = shapeProps("rectangle");
    setTransform(top, Transform::translate(Vec3(0, 0, thickness)));
    setTransform(bottom, Transform::translate(Vec3(0, 0, 0)) * Transform::rotate(Vec3(1, 0, 0), 180.0));
    Properties slab = shapeProps("cube");
    setTransform(slab, Transform::translate(Vec3(5, 0, 0)) * Transform::scale(Vec3(1, 1, thickness / 2)));
    Properties disk = shapeProps("disk");
    setTransform(disk, Transform::translate(Vec3(-5, 0, -thickness)));
    Properties disk2 = shapeProps("disk");
    setTransform(disk2, Transform::translate(Vec3(-5, 0, 0)));
    auto scene = makeScene({makeShape(top), makeShape(bottom), makeShape(slab), makeShape(disk), makeShape(disk2)});
    PCG32 rng(4, 4);
    int leaks = 0;
    for (int i = 0; i < 30000; ++i) {
        const double cx = (i % 3 - 1) * 5.0;
        const Vec3 aim(cx + (rng.nextDouble() - 0.5) * 0.8, (rng.nextDouble() - 0.5) * 0.8, 0);
        Intersection its, next;
        ASSERT_TRUE(scene->intersect(Ray(aim + Vec3(0, 0, 1), Vec3(0, 0, -1)), its));
        // Steeply enough downwards that the other layer lies within the shape's extent.
        Vec3 down = hemisphere(Vec3(0, 0, -1), rng);
        if (down.z > -0.3) down = normalize(Vec3(down.x, down.y, -0.3));
        if (!scene->intersect(scene->spawnRay(its, down), next)) {
            ++leaks;
            continue;
        }
        // The hit is the lower layer.
        if (std::abs(its.p.z - next.p.z - thickness) > 1e-9) ++leaks;
    }
    EXPECT_EQ(leaks, 0);
}

TEST(RayOffset, EpsilonGrowsWithMagnitude) {
    auto scene = makeScene({makeShape(shapeProps("sphere"))});
    const double e0 = scene->epsilonAt(Vec3(0.0)), e1 = scene->epsilonAt(Vec3(1e3, -5, 2));
    EXPECT_GT(e0, 0.0);
    EXPECT_LT(e0, 1e-3);
    // Far from the origin: many single-precision ulps of the coordinates, yet a small fraction of them.
    EXPECT_GT(e1, 64 * 1e3 * 0x1p-24);
    EXPECT_LT(e1, 1e-4 * 1e3);
    EXPECT_DOUBLE_EQ(scene->epsilonAt(Vec3(-1e3, 0, 0)), e1);
    EXPECT_DOUBLE_EQ(scene->epsilonAt(Vec3(0, 0, -1e3)), e1);
}

// Shadow rays between surface points: unoccluded between two facing surfaces, occluded with a blocker.
TEST(ShadowRays, SpawnRayTo) {
    Properties a = shapeProps("rectangle"), b = shapeProps("rectangle");
    setTransform(b, Transform::translate(Vec3(0, 0, 2)) * Transform::rotate(Vec3(1, 0, 0), 180.0));
    auto scene = makeScene({makeShape(a), makeShape(b)});
    PCG32 rng(1, 2);
    for (int i = 0; i < 2000; ++i) {
        Intersection lo, hi;
        const Vec3 pa(rng.nextDouble() * 1.8 - 0.9, rng.nextDouble() * 1.8 - 0.9, 0);
        const Vec3 pb(rng.nextDouble() * 1.8 - 0.9, rng.nextDouble() * 1.8 - 0.9, 2);
        ASSERT_TRUE(scene->intersect(Ray(pa + Vec3(0, 0, 1), Vec3(0, 0, -1)), lo));
        ASSERT_TRUE(scene->intersect(Ray(pb - Vec3(0, 0, 1), Vec3(0, 0, 1)), hi));
        EXPECT_FALSE(scene->occluded(scene->spawnRayTo(lo, hi.p)));
        EXPECT_FALSE(scene->occluded(scene->spawnRayTo(hi, lo.p)));
        const Ray r = scene->spawnRayTo(lo, hi.p);
        EXPECT_NEAR((r(r.tmax) - hi.p).length(), 0.0, 1e-3);
    }
    Properties blocker = shapeProps("sphere");
    setPoint(blocker, "center", Vec3(0, 0, 1));
    setFloat(blocker, "radius", 0.2);
    auto blocked = makeScene({makeShape(a), makeShape(b), makeShape(blocker)});
    Intersection lo;
    ASSERT_TRUE(blocked->intersect(Ray(Vec3(0.01, 0, 0.5), Vec3(0, 0, -1)), lo));
    EXPECT_TRUE(blocked->occluded(blocked->spawnRayTo(lo, Vec3(0, 0.01, 2))));
    EXPECT_TRUE(blocked->occluded(blocked->spawnRayTo(Vec3(0, 0, 0.5), Vec3(0, 0, 1.5))));
    EXPECT_FALSE(blocked->occluded(blocked->spawnRayTo(Vec3(0.5, 0, 0.5), Vec3(0.5, 0, 1.5))));
}

TEST(SceneQueries, RayCounterIsPerThread) {
    auto scene = makeScene({makeShape(shapeProps("sphere"))});
    const uint64_t before = Scene::threadRayCount();
    Intersection its;
    for (int i = 0; i < 10; ++i) scene->intersect(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)), its);
    for (int i = 0; i < 5; ++i) scene->occluded(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)));
    EXPECT_EQ(Scene::threadRayCount() - before, 15u);
    uint64_t other = 0;
    std::thread t([&] {
        const uint64_t start = Scene::threadRayCount();
        Intersection local;
        for (int i = 0; i < 7; ++i) scene->intersect(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)), local);
        other = Scene::threadRayCount() - start;
    });
    t.join();
    EXPECT_EQ(other, 7u);
    EXPECT_EQ(Scene::threadRayCount() - before, 15u);
}

// bench_pathtracer's replay: while a log is set, each ray the thread traces is recorded with its kind, in
// order; other threads and queries after the log is unset are not; traverse gives the recorded queries'
// answers again. A sphere (analytic, Embree user geometry, which needs the double-precision query ray) and a
// rectangle (triangles).
TEST(SceneQueries, RecordedRaysReplayWithTheSameAnswers) {
    Properties rect = shapeProps("rectangle");
    setTransform(rect, Transform::translate(Vec3(0, 0, -2)) * Transform::scale(Vec3(3.0)));
    auto scene = makeScene({makeShape(shapeProps("sphere")), makeShape(rect)});
    std::vector<Scene::TracedRay> log;
    std::vector<bool> answers;
    PCG32 rng(3, 5);
    Scene::recordThreadRays(&log);
    for (int i = 0; i < 200; ++i) {
        const Vec3 o(rng.nextDouble() * 4 - 2, rng.nextDouble() * 4 - 2, 3.0);
        const Vec3 d = normalize(Vec3(rng.nextDouble() - 0.5, rng.nextDouble() - 0.5, -1.0));
        Intersection its;
        if (i % 3 == 0)
            answers.push_back(scene->occluded(Ray(o, d, 0.0, 4.0)));
        else
            answers.push_back(scene->intersect(Ray(o, d), its));
    }
    std::thread([&] {
        Intersection its;
        scene->intersect(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)), its);
    }).join();
    Scene::recordThreadRays(nullptr);
    scene->occluded(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)));
    ASSERT_EQ(log.size(), answers.size());
    int hits = 0;
    for (size_t i = 0; i < log.size(); ++i) {
        EXPECT_EQ(log[i].shadow, i % 3 == 0) << i;
        EXPECT_EQ(scene->traverse(log[i]), answers[i]) << i;
        hits += answers[i];
    }
    // Both answers occur (rays above the sphere miss it and hit the rectangle or nothing).
    EXPECT_GT(hits, 20);
    EXPECT_LT(hits, 190);
}

TEST(SceneQueries, BoundsAndPrimitiveCount) {
    Properties s = shapeProps("sphere");
    setPoint(s, "center", Vec3(1, 2, 3));
    Properties c = shapeProps("cube");
    setTransform(c, Transform::translate(Vec3(-4, 0, 0)));
    auto scene = makeScene({makeShape(s), makeShape(c)});
    EXPECT_EQ(scene->primitiveCount(), 13u);
    const AABB &b = scene->bounds();
    EXPECT_NEAR(b.min.x, -5, 1e-12);
    EXPECT_NEAR(b.max.x, 2, 1e-12);
    EXPECT_NEAR(b.min.y, -1, 1e-12);
    EXPECT_NEAR(b.max.y, 3, 1e-12);
    EXPECT_NEAR(b.min.z, -1, 1e-12);
    EXPECT_NEAR(b.max.z, 4, 1e-12);
}

TEST(SceneQueries, FinalizeRejectsIncompleteScenes) {
    Scene noSensor;
    noSensor.addShape(makeShape(shapeProps("sphere")));
    EXPECT_THROW(noSensor.finalize(), SceneError);
    Scene empty;
    empty.setSensor(makeSensor());
    EXPECT_THROW(empty.finalize(), SceneError);
    // Emitters alone make a scene.
    Scene lightsOnly;
    lightsOnly.setSensor(makeSensor());
    lightsOnly.addEmitter(makeEmitter("point", 1.0));
    EXPECT_NO_THROW(lightsOnly.finalize());
    EXPECT_TRUE(lightsOnly.bounds().valid());
    Intersection its;
    EXPECT_FALSE(lightsOnly.intersect(Ray(Vec3(0.0), Vec3(0, 0, 1)), its));
}

// Emitters are selected in proportion to samplingWeight; sampleEmitterDirect folds the selection
// probability into both the density and the returned weight.
TEST(EmitterSelection, ProportionalToSamplingWeight) {
    auto scene = std::make_unique<Scene>();
    auto p1 = makeEmitter("point", 1.0), p2 = makeEmitter("point", 3.0);
    scene->addEmitter(p1);
    scene->addEmitter(p2);
    // An area light on a sphere, weight 1 (the default).
    Properties e(ObjectKind::Emitter, "area", kLoc);
    auto area = std::dynamic_pointer_cast<Emitter>((*findPlugin(ObjectKind::Emitter, "area"))(e, {}));
    Properties s = shapeProps("sphere");
    setPoint(s, "center", Vec3(0, 0, 5));
    s.addChild({"", ObjectKind::Emitter, area, kLoc});
    scene->addShape(makeShape(s));
    scene->setSensor(makeSensor());
    scene->finalize();
    ASSERT_EQ(scene->emitters().size(), 3u);
    EXPECT_DOUBLE_EQ(scene->emitterPmf(p1.get()), 0.2);
    EXPECT_DOUBLE_EQ(scene->emitterPmf(p2.get()), 0.6);
    EXPECT_DOUBLE_EQ(scene->emitterPmf(area.get()), 0.2);
    EXPECT_EQ(scene->environment(), nullptr);

    PCG32 rng(5, 6);
    std::vector<double> counts(3, 0.0);
    const int n = 50000;
    for (int i = 0; i < n; ++i) {
        double pmf;
        const Emitter *chosen = scene->sampleEmitter(rng.nextDouble(), pmf);
        const size_t k = chosen == p1.get() ? 0 : (chosen == p2.get() ? 1 : 2);
        EXPECT_DOUBLE_EQ(pmf, scene->emitterPmf(chosen));
        counts[k] += 1;
    }
    EXPECT_NEAR(counts[0] / n, 0.2, 0.01);
    EXPECT_NEAR(counts[1] / n, 0.6, 0.01);
    EXPECT_NEAR(counts[2] / n, 0.2, 0.01);

    int areaSamples = 0;
    for (int i = 0; i < 2000; ++i) {
        DirectSample ds(Vec3(0.3, -0.2, 0), Vec3(0, 0, 1));
        const double u1 = rng.nextDouble();
        const Spectrum w = scene->sampleEmitterDirect(ds, Vec2(u1, rng.nextDouble()));
        const auto *chosen = static_cast<const Emitter *>(ds.object);
        ASSERT_NE(chosen, nullptr);
        const double pmf = scene->emitterPmf(chosen);
        // The emitter's own sample with the same remapped random number must differ by the pmf only.
        EXPECT_NEAR(scene->pdfEmitterDirect(ds, chosen), chosen->pdfDirect(ds) * pmf, 1e-12 * ds.pdf);
        if (chosen == area.get()) {
            ++areaSamples;
            EXPECT_NEAR(ds.pdf, area->pdfDirect(ds) * pmf, 1e-9 * ds.pdf);
            EXPECT_NEAR(scene->pdfEmitterDirect(ds, chosen), ds.pdf, 1e-9 * ds.pdf);
            // Radiance 1 arriving: weight = 1 / pdf (selection included).
            EXPECT_NEAR(w.r * ds.pdf, 1.0, 1e-9);
        } else {
            EXPECT_EQ(ds.measure, Measure::Discrete);
            EXPECT_DOUBLE_EQ(ds.pdf, pmf);
            DirectSample own(ds.ref, ds.refN);
            const Spectrum direct = chosen->sampleDirect(own, Vec2(0.5, 0.5));
            EXPECT_NEAR(w.r * pmf, direct.r, 1e-12 * direct.r);
        }
    }
    EXPECT_GT(areaSamples, 200);
}

TEST(EmitterSelection, OnlyOneEnvironment) {
    Scene scene;
    scene.addShape(makeShape(shapeProps("sphere")));
    scene.addEmitter(makeEmitter("constant", 1.0));
    scene.setSensor(makeSensor());
    scene.finalize();
    ASSERT_NE(scene.environment(), nullptr);
    Scene two;
    two.addShape(makeShape(shapeProps("sphere")));
    two.addEmitter(makeEmitter("constant", 1.0));
    two.addEmitter(makeEmitter("constant", 1.0));
    two.setSensor(makeSensor());
    EXPECT_THROW(two.finalize(), SceneError);
}

// Shapes through the XML loader: mesh files, a shape group placed twice, an emitting sphere.
TEST(LoaderIntegration, ShapesFromXml) {
    const std::string dir = tempDir("scene-xml-shapes");
    writeFile(dir, "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    writeFile(dir, "scene.xml", R"(<scene version="0.6.0">
  <sensor type="perspective"><transform name="toWorld"><lookat origin="0,0,10" target="0,0,0" up="0,1,0"/></transform></sensor>
  <shape type="shapegroup" id="group">
    <shape type="obj"><string name="filename" value="tri.obj"/></shape>
  </shape>
  <shape type="instance"><ref id="group"/><transform name="toWorld"><translate x="3"/></transform></shape>
  <shape type="instance"><ref id="group"/><transform name="toWorld"><translate x="-3"/></transform></shape>
  <shape type="sphere">
    <point name="center" x="0" y="0" z="-2"/><float name="radius" value="0.5"/>
    <emitter type="area"><rgb name="radiance" value="2"/></emitter>
  </shape>
</scene>)");
    auto scene = loadScene(dir + "/scene.xml");
    EXPECT_EQ(scene->shapes().size(), 3u);
    EXPECT_EQ(scene->emitters().size(), 1u);
    Intersection its;
    ASSERT_TRUE(scene->intersect(Ray(Vec3(3.2, 0.2, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 5.0, 1e-12);
    ASSERT_TRUE(scene->intersect(Ray(Vec3(-2.8, 0.2, 5), Vec3(0, 0, -1)), its));
    EXPECT_FALSE(scene->intersect(Ray(Vec3(0.2, 0.2, 5), Vec3(0, 0, 1)), its));
    ASSERT_TRUE(scene->intersect(Ray(Vec3(0, 0, 5), Vec3(0, 0, -1)), its));
    EXPECT_NEAR(its.t, 6.5, 1e-12);
    ASSERT_TRUE(its.isEmitter());
    EXPECT_NEAR(its.Le(Vec3(0, 0, 1)).r, 2.0, 1e-12);
    EXPECT_TRUE(its.Le(Vec3(0, 0, -1)).isBlack());
    // A mesh file that is not there: an error naming the parameter's line in the scene file.
    writeFile(dir, "bad.xml", R"(<scene version="0.6.0">
  <sensor type="perspective"/>
  <shape type="ply">
    <string name="filename" value="missing.ply"/>
  </shape>
</scene>)");
    try {
        loadScene(dir + "/bad.xml");
        ADD_FAILURE() << "no error for a missing mesh";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("missing.ply"), std::string::npos) << e.what();
        EXPECT_EQ(e.location().line, 4) << e.what();
    }
}

}  // namespace
}  // namespace pf::test
