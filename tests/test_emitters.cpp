// Emitters: chi-square tests of every direction density (emission directions for light tracing, and
// directions seen from a reference point for next-event estimation), position densities, power, the
// agreement of direct sampling with the position x direction split that BDPT evaluates, the envmap's
// orientation and normalization, and bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

#include "emitter/environment.h"
#include "image/bitmap.h"
#include "scene/plugins.h"
#include "scene/shape.h"
#include "support/chi2.h"
#include "support/emitter_checks.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

const SourceLocation kLoc = kEmitterTestLoc;
constexpr int kChi2Tests = 8;  // chi-square tests in this file, for the multiple-test correction

// Densities that jump (at the edge of a rectangle or of a sphere's cone, between envmap pixels) need a
// finer integration grid in the cells the jumps cut than Simpson's default 6 x 6 gives, or the expected
// counts there are off by more than the statistical noise.
constexpr int kFineIntegration = 40;

Chi2Options chi2Options(int thetaBins = 10, int phiBins = 20, int integrationRes = 6) {
    return emitterChi2Options(kChi2Tests, thetaBins, phiBins, integrationRes);
}

std::shared_ptr<Shape> makeShape(const Properties &p) {
    return std::dynamic_pointer_cast<Shape>((*findPlugin(ObjectKind::Shape, p.pluginName()))(p, LoadContext{}));
}

// An area emitter on a shape, with the surface intersection the tests need to evaluate pdfDirect for a
// direction (Mitsuba's rectangle is [-1, 1]^2 in the local xy plane with normal +z).
struct AreaLight {
    std::shared_ptr<Shape> shape;
    std::shared_ptr<Emitter> emitter;
    std::function<bool(const Vec3 &o, const Vec3 &d, DirectSample &ds)> hit;
};

AreaLight areaLight(const Properties &shapeProps, const Spectrum &radiance) {
    Properties e = props(ObjectKind::Emitter, "area");
    setSpectrum(e, "radiance", radiance);
    AreaLight light;
    light.emitter = makeEmitter(e);
    Properties s = shapeProps;
    s.addChild({"", ObjectKind::Emitter, light.emitter, kLoc});
    light.shape = makeShape(s);
    light.emitter->setShape(light.shape.get());
    return light;
}

AreaLight rectangleLight(const Transform &toWorld, const Spectrum &radiance) {
    Properties s = props(ObjectKind::Shape, "rectangle");
    setTransform(s, "toWorld", toWorld);
    AreaLight light = areaLight(s, radiance);
    light.hit = [toWorld](const Vec3 &o, const Vec3 &d, DirectSample &ds) {
        const Transform inv = toWorld.inverse();
        const Vec3 lo = inv.point(o), ld = inv.vector(d);
        const double t = -lo.z / ld.z;
        const Vec3 q = lo + ld * t;
        if (!(t > 0) || std::abs(q.x) > 1 || std::abs(q.y) > 1) return false;
        ds.p = o + d * t;
        ds.n = normalize(toWorld.normal(Vec3(0, 0, 1)));
        ds.d = d;
        ds.dist = t;
        return true;
    };
    return light;
}

AreaLight sphereLight(const Vec3 &center, double radius, const Spectrum &radiance) {
    Properties s = props(ObjectKind::Shape, "sphere");
    s.set("center", Properties::Type::Point, center, kLoc);
    setFloat(s, "radius", radius);
    AreaLight light = areaLight(s, radiance);
    light.hit = [center, radius](const Vec3 &o, const Vec3 &d, DirectSample &ds) {
        const Vec3 oc = o - center;
        const double b = dot(oc, d), c = oc.lengthSquared() - radius * radius, disc = b * b - c;
        if (disc < 0) return false;
        const double t = -b - std::sqrt(disc);
        if (!(t > 0)) return false;
        ds.p = o + d * t;
        ds.n = normalize(ds.p - center);
        ds.d = d;
        ds.dist = t;
        return true;
    };
    return light;
}

// The rectangle used by most area tests: 4 x 1 (area 4), tilted, off the origin.
const Transform kRectToWorld = Transform::translate(Vec3(0.3, -0.2, 1.5)) * Transform::rotate(Vec3(1, 1, 0), 50) *
                               Transform::scale(Vec3(2, 0.5, 1));

// ---- area ----

TEST(AreaEmitter, PositionsAreUniformByArea) {
    const AreaLight rect = rectangleLight(kRectToWorld, Spectrum(1.0));
    const AreaLight sphere = sphereLight(Vec3(1, 2, 3), 0.7, Spectrum(1.0));
    PCG32 rng(1, 1);
    for (const auto *light : {&rect, &sphere}) {
        const double area = light->shape->surfaceArea();
        for (int i = 0; i < 100; ++i) {
            PositionSample ps;
            const Spectrum w = light->emitter->samplePosition(ps, {rng.nextDouble(), rng.nextDouble()});
            EXPECT_EQ(ps.measure, Measure::Area);
            EXPECT_NEAR(ps.pdf, 1.0 / area, 1e-12);
            EXPECT_NEAR(light->emitter->pdfPosition(ps), 1.0 / area, 1e-12);
            EXPECT_NEAR(w.g, kPi * area, 1e-9);  // pi L / pdf
        }
    }
    EXPECT_NEAR(rect.shape->surfaceArea(), 4.0, 1e-12);
    EXPECT_NEAR(sphere.shape->surfaceArea(), 4 * kPi * 0.49, 1e-12);
}

TEST(AreaEmitter, PowerOfUnitAreaLight) {
    const Spectrum L(1.0, 2.0, 0.5);
    const AreaLight unit = rectangleLight(Transform::scale(Vec3(0.5, 0.5, 1)), L);
    ASSERT_NEAR(unit.shape->surfaceArea(), 1.0, 1e-12);
    const Spectrum p = unit.emitter->power();
    EXPECT_NEAR(p.r, kPi * L.r, 1e-12);
    EXPECT_NEAR(p.g, kPi * L.g, 1e-12);
    EXPECT_NEAR(p.b, kPi * L.b, 1e-12);
    const AreaLight rect = rectangleLight(kRectToWorld, L);
    EXPECT_NEAR(rect.emitter->power().g, kPi * 2.0 * 4.0, 1e-9);
    expectLightTracingPower(*rect.emitter);
}

TEST(AreaEmitter, EmissionDirectionsChiSquare) {
    const AreaLight rect = rectangleLight(kRectToWorld, Spectrum(1.0));
    PositionSample ps;
    rect.emitter->samplePosition(ps, {0.3, 0.6});
    const auto r = emissionChi2(*rect.emitter, ps, chi2Options());
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 1e-3);
}

TEST(AreaEmitter, DirectSamplingChiSquareRectangle) {
    const AreaLight rect = rectangleLight(kRectToWorld, Spectrum(1.0));
    // A reference point close enough for the rectangle to cover a wide solid angle, on its emitting side.
    const Vec3 ref = kRectToWorld.point(Vec3(0.2, -0.3, 0.8));
    const auto r = directChi2(*rect.emitter, ref, rect.hit, chi2Options(40, 40, kFineIntegration));
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.sampledMass, 1.0, 0);
}

TEST(AreaEmitter, DirectSamplingChiSquareSphere) {
    const Vec3 center(0.5, -0.5, 1.0);
    const AreaLight sphere = sphereLight(center, 0.8, Spectrum(1.0));
    const auto r = directChi2(*sphere.emitter, Vec3(0.1, 0.2, -0.3), sphere.hit, chi2Options(40, 40, kFineIntegration));
    EXPECT_TRUE(r.passed) << r.report;
}

TEST(AreaEmitter, DirectSamplingMatchesSplitAndIsOneSided) {
    const Spectrum L(1.0, 2.0, 3.0);
    const AreaLight rect = rectangleLight(kRectToWorld, L);
    const AreaLight sphere = sphereLight(Vec3(0.5, -0.5, 1.0), 0.8, L);
    const Vec3 front = kRectToWorld.point(Vec3(0.1, 0.1, 2)), back = kRectToWorld.point(Vec3(0.1, 0.1, -2));
    expectDirectMatchesSplit(*rect.emitter, {front, kRectToWorld.point(Vec3(3, -2, 0.5))});
    expectDirectMatchesSplit(*sphere.emitter, {Vec3(3, 0, 0), Vec3(0, 0, -4)});
    // Light leaves only the side the normal points to.
    PCG32 rng(2, 2);
    for (int i = 0; i < 100; ++i) {
        DirectSample ds(back, Vec3(0.0));
        EXPECT_TRUE(rect.emitter->sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()}).isBlack());
        ds = DirectSample(front, Vec3(0.0));
        EXPECT_FALSE(rect.emitter->sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()}).isBlack());
        Intersection its;
        its.n = ds.n;
        EXPECT_EQ(rect.emitter->eval(its, -ds.d), L);
        EXPECT_TRUE(rect.emitter->eval(its, ds.d).isBlack());
    }
}

// ---- point and spot ----

TEST(PointEmitter, IntensityAndSplit) {
    Properties p = props(ObjectKind::Emitter, "point");
    setSpectrum(p, "intensity", Spectrum(2.0, 3.0, 4.0));
    p.set("position", Properties::Type::Point, Vec3(1, 2, 3), kLoc);
    const auto e = makeEmitter(p);
    EXPECT_TRUE(e->isDelta());
    DirectSample ds(Vec3(1, 2, 1), Vec3(0.0));
    const Spectrum v = e->sampleDirect(ds, {0.5, 0.5});
    EXPECT_NEAR(v.g, 3.0 / 4.0, 1e-12);
    EXPECT_EQ(ds.measure, Measure::Discrete);
    EXPECT_NEAR(ds.dist, 2.0, 1e-12);
    EXPECT_NEAR(e->power().r, 8 * kPi, 1e-12);
    expectDirectMatchesSplit(*e, {Vec3(0.0), Vec3(5, -1, 2)});
    expectLightTracingPower(*e, 1000);

    Properties q = props(ObjectKind::Emitter, "point");
    setTransform(q, "toWorld", Transform::translate(Vec3(1, 2, 3)));
    ds = DirectSample(Vec3(1, 2, 1), Vec3(0.0));
    makeEmitter(q)->sampleDirect(ds, {0.5, 0.5});
    EXPECT_NEAR((ds.p - Vec3(1, 2, 3)).length(), 0, 1e-12);
}

Properties spotProps() {
    Properties p = props(ObjectKind::Emitter, "spot");
    setSpectrum(p, "intensity", Spectrum(5.0));
    setFloat(p, "cutoffAngle", 60);
    setFloat(p, "beamWidth", 30);
    setTransform(p, "toWorld", Transform::lookAt(Vec3(1, 1, 1), Vec3(1, 2, 1), Vec3(0, 0, 1)));
    return p;
}

TEST(SpotEmitter, ConeChiSquare) {
    Properties p = props(ObjectKind::Emitter, "spot");
    setFloat(p, "cutoffAngle", 60);
    setFloat(p, "beamWidth", 30);
    const auto e = makeEmitter(p);
    PositionSample ps;
    e->samplePosition(ps, {0.5, 0.5});
    const auto r = emissionChi2(*e, ps, chi2Options(40, 20));
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 2e-3);
}

// Mitsuba's falloff: full intensity inside beamWidth, linear in angle down to zero at cutoffAngle.
TEST(SpotEmitter, FalloffProfile) {
    const auto e = makeEmitter(spotProps());
    const Vec3 pos(1, 1, 1), axis(0, 1, 0), side(1, 0, 0);
    for (const double deg : {0.0, 20.0, 30.0, 37.5, 45.0, 52.5, 59.0, 61.0, 120.0}) {
        const double a = degToRad(deg);
        const Vec3 dir = axis * std::cos(a) + side * std::sin(a);
        const double expected = deg <= 30 ? 1.0 : deg >= 60 ? 0.0 : (60 - deg) / 30;
        DirectSample ds(pos + dir * 2.0, Vec3(0.0));
        EXPECT_NEAR(e->sampleDirect(ds, {0.5, 0.5}).r, 5.0 * expected / 4.0, 1e-9) << deg;
        PositionSample ps;
        e->samplePosition(ps, {0.5, 0.5});
        DirectionSample dd;
        dd.d = dir;
        EXPECT_NEAR((e->evalPosition(ps) * e->evalDirection(dd, ps)).r, 5.0 * expected, 1e-9) << deg;
    }
}

// power() against a numerical integral of the falloff, and against light tracing.
TEST(SpotEmitter, Power) {
    const auto e = makeEmitter(spotProps());
    const int n = 20000;
    double integral = 0;
    for (int i = 0; i < n; ++i) {  // midpoint rule in theta
        const double t = (i + 0.5) * kPi / n, deg = radToDeg(t);
        const double f = deg <= 30 ? 1.0 : deg >= 60 ? 0.0 : (60 - deg) / 30;
        integral += f * std::sin(t) * (kPi / n) * 2 * kPi;
    }
    EXPECT_NEAR(e->power().r, 5.0 * integral, 1e-6);
    expectLightTracingPower(*e);
    expectDirectMatchesSplit(*e, {Vec3(1, 3, 1), Vec3(1.5, 2, 1.2)});
}

// ---- directional ----

TEST(DirectionalEmitter, IrradianceAndEntryDisk) {
    Properties p = props(ObjectKind::Emitter, "directional");
    setSpectrum(p, "irradiance", Spectrum(3.0));
    p.set("direction", Properties::Type::Vector, Vec3(1, -2, 0.5), kLoc);
    const auto e = makeEmitter(p);
    auto *infinite = dynamic_cast<InfiniteEmitter *>(e.get());
    ASSERT_NE(infinite, nullptr);
    const Vec3 center(1, 2, 3), dir = normalize(Vec3(1, -2, 0.5));
    const double radius = 4;
    infinite->setBoundingSphere(center, radius);
    DirectSample ds(Vec3(2, 2, 2), Vec3(0.0));
    EXPECT_EQ(e->sampleDirect(ds, {0.1, 0.2}), Spectrum(3.0));
    EXPECT_NEAR((ds.d + dir).length(), 0, 1e-12);
    EXPECT_EQ(ds.measure, Measure::Discrete);
    EXPECT_NEAR(e->power().r, 3.0 * kPi * radius * radius, 1e-9);

    // Light tracing: the flux through a disk of radius 1 facing the light equals irradiance * pi.
    PCG32 rng(4, 4);
    const int n = 400000;
    double sum = 0, sumSq = 0;
    for (int i = 0; i < n; ++i) {
        PositionSample ps;
        const Spectrum wp = e->samplePosition(ps, {rng.nextDouble(), rng.nextDouble()});
        EXPECT_NEAR(dot(ps.p - center, dir), -radius, 1e-9);  // on the entry disk's plane
        DirectionSample dd;
        const Spectrum wd = e->sampleDirection(dd, ps, {rng.nextDouble(), rng.nextDouble()});
        EXPECT_EQ(dd.measure, Measure::Discrete);
        const Vec3 toAxis = (ps.p - center) - dir * dot(ps.p - center, dir);
        const double v = toAxis.length() < 1.0 ? (wp * wd).r : 0.0;
        sum += v;
        sumSq += v * v;
    }
    const double mean = sum / n, stderr_ = std::sqrt((sumSq / n - mean * mean) / n);
    EXPECT_NEAR(mean, 3.0 * kPi, 4 * stderr_);
}

TEST(DirectionalEmitter, ToWorldGivesDirection) {
    Properties p = props(ObjectKind::Emitter, "directional");
    setTransform(p, "toWorld", Transform::rotate(Vec3(1, 0, 0), 90));  // local +z -> world -y
    const auto e = makeEmitter(p);
    DirectSample ds(Vec3(0.0), Vec3(0.0));
    e->sampleDirect(ds, {0.5, 0.5});
    EXPECT_NEAR((ds.d - Vec3(0, 1, 0)).length(), 0, 1e-12);
}

// ---- constant ----

std::shared_ptr<Emitter> constantEmitter(const Spectrum &L) {
    Properties p = props(ObjectKind::Emitter, "constant");
    setSpectrum(p, "radiance", L);
    auto e = makeEmitter(p);
    dynamic_cast<InfiniteEmitter &>(*e).setBoundingSphere(Vec3(1, 0, -1), 3.0);
    return e;
}

TEST(ConstantEmitter, ChiSquareAndSphere) {
    const Spectrum L(0.5, 1.0, 2.0);
    const auto e = constantEmitter(L);
    EXPECT_TRUE(e->isEnvironment());
    const Vec3 ref(1.5, 0.5, -0.5);
    auto hit = [&](const Vec3 &o, const Vec3 &d, DirectSample &ds) { return environmentHit(*e, o, d, ds); };
    auto r = directChi2(*e, ref, hit, chi2Options());
    EXPECT_TRUE(r.passed) << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 1e-3);

    PositionSample ps;
    e->samplePosition(ps, {0.2, 0.7});
    EXPECT_NEAR((ps.p - Vec3(1, 0, -1)).length(), 3.0, 1e-12);
    EXPECT_NEAR(ps.pdf, 1.0 / (4 * kPi * 9), 1e-12);
    r = emissionChi2(*e, ps, chi2Options());
    EXPECT_TRUE(r.passed) << r.report;

    EXPECT_EQ(e->evalEnvironment(Ray(ref, normalize(Vec3(1, 2, 3)))), L);
    DirectSample ds;
    ASSERT_TRUE(e->fillDirectSample(ds, Ray(ref, Vec3(0, 0, 1))));
    EXPECT_NEAR((ds.p - Vec3(1, 0, -1)).length(), 3.0, 1e-12);
    EXPECT_GT(dot(ds.n, Vec3(0, 0, -1)), 0.9);  // inward, facing ref
    EXPECT_NEAR(e->power().g, 1.0 * 4 * kPi * kPi * 9, 1e-9);
    expectLightTracingPower(*e);
    expectDirectMatchesSplit(*e, {ref, Vec3(1, 0, -1)});
}

// ---- envmap ----

// A 32 x 16 lat-long map with a horizontal gradient, a bright spot, a coloured band and a black block, so
// that importance sampling, orientation and the sin(theta) weighting all matter.
Bitmap testMap() {
    Bitmap b(32, 16);
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) {
            Spectrum v(0.1 + 0.05 * x, 0.2 + 0.01 * y, 0.3);
            if (x >= 20 && x < 23 && y >= 4 && y < 6) v = Spectrum(40.0, 30.0, 20.0);
            if (y == 10) v = Spectrum(0.0, 0.0, 3.0);
            if (x < 4 && y < 3) v = Spectrum(0.0);
            b.set(x, y, v);
        }
    return b;
}

struct EnvMapFixture {
    std::string dir;
    LoadContext ctx;
    Bitmap map = testMap();
    Transform toWorld = Transform::rotate(Vec3(0.3, 1, 0.2), 70);
    double scale = 1.5;
    EnvMapFixture() {
        dir = tempDir("test_emitters_envmap");
        writeEXR(dir + "/map.exr", map);
        ctx.sceneDir = ctx.rootDir = dir;
    }
    Properties properties() const {
        Properties p = props(ObjectKind::Emitter, "envmap");
        p.set("filename", Properties::Type::String, std::string("map.exr"), kLoc);
        setFloat(p, "scale", scale);
        setTransform(p, "toWorld", toWorld);
        return p;
    }
    std::shared_ptr<Emitter> emitter() const {
        auto e = makeEmitter(properties(), ctx);
        dynamic_cast<InfiniteEmitter &>(*e).setBoundingSphere(Vec3(0, 1, 0), 2.0);
        return e;
    }
    // The map pixel a world direction sees, by Mitsuba's lat-long convention, written out independently.
    Spectrum pixel(const Vec3 &worldDir) const {
        const Vec3 v = normalize(toWorld.inverse().vector(worldDir));
        double u = std::atan2(v.x, -v.z) / (2 * kPi);
        if (u < 0) u += 1;
        const double t = std::acos(clamp(v.y, -1.0, 1.0)) / kPi;
        const int x = std::min(int(u * map.width), map.width - 1), y = std::min(int(t * map.height), map.height - 1);
        return map.get(x, y) * scale;
    }
};

TEST(EnvMapEmitter, OrientationOfTheMap) {
    EnvMapFixture f;
    f.toWorld = Transform();
    const auto e = f.emitter();
    // +y is the zenith (top row), -y the nadir, -z the left edge / +z the centre column, +x a quarter in.
    EXPECT_EQ(e->evalEnvironment(Ray(Vec3(0.0), normalize(Vec3(0, 1, -0.01)))), f.map.get(0, 0) * f.scale);
    EXPECT_EQ(e->evalEnvironment(Ray(Vec3(0.0), normalize(Vec3(0, -1, -0.01)))), f.map.get(0, 15) * f.scale);
    EXPECT_EQ(e->evalEnvironment(Ray(Vec3(0.0), normalize(Vec3(0, 0.01, 1)))), f.map.get(16, 7) * f.scale);
    EXPECT_EQ(e->evalEnvironment(Ray(Vec3(0.0), normalize(Vec3(1, -0.01, -0.01)))), f.map.get(7, 8) * f.scale);
}

TEST(EnvMapEmitter, DirectSamplingChiSquareAndPixelMatch) {
    EnvMapFixture f;
    const auto e = f.emitter();
    const Vec3 ref(0.2, 0.8, -0.3);
    auto hit = [&](const Vec3 &o, const Vec3 &d, DirectSample &ds) { return environmentHit(*e, o, d, ds); };
    const auto r = directChi2(*e, ref, hit, chi2Options(32, 32, kFineIntegration));
    EXPECT_TRUE(r.passed) << r.report;

    // What direct sampling returns is the map pixel in that direction over the pdf.
    PCG32 rng(8, 8);
    int bright = 0;
    for (int i = 0; i < 20000; ++i) {
        DirectSample ds(ref, Vec3(0.0));
        const Spectrum v = e->sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()});
        ASSERT_GT(ds.pdf, 0);
        const Spectrum expected = f.pixel(ds.d);
        ASSERT_FALSE(expected.isBlack());  // black pixels are never sampled
        ASSERT_EQ(e->evalEnvironment(Ray(ref, ds.d)), expected);
        EXPECT_NEAR(v.r * ds.pdf, expected.r, 1e-9 * expected.r);
        bright += expected.r > 50;
    }
    // The bright spot holds 6 of 512 pixels but most of the power: importance sampling finds it.
    EXPECT_GT(bright, 20000 / 4);
}

TEST(EnvMapEmitter, EmissionChiSquare) {
    EnvMapFixture f;
    const auto e = f.emitter();
    PositionSample ps;
    e->samplePosition(ps, {0.4, 0.1});
    const auto r = emissionChi2(*e, ps, chi2Options(32, 32, kFineIntegration));
    EXPECT_TRUE(r.passed) << r.report;
}

// The solid-angle density integrates to 1 over the sphere (midpoint rule in cos theta and phi, in world
// coordinates, which the rotation keeps unaligned with the map's pixels).
TEST(EnvMapEmitter, PdfIntegratesToOne) {
    EnvMapFixture f;
    const auto e = f.emitter();
    const int nz = 1000, nphi = 2000;
    double integral = 0;
    for (int i = 0; i < nz; ++i) {
        const double z = -1 + (i + 0.5) * 2.0 / nz, s = std::sqrt(1 - z * z);
        for (int j = 0; j < nphi; ++j) {
            const double phi = (j + 0.5) * 2 * kPi / nphi;
            DirectSample ds(Vec3(0.0), Vec3(0.0));
            ds.d = Vec3(s * std::cos(phi), s * std::sin(phi), z);
            integral += e->pdfDirect(ds);
        }
    }
    integral *= (2.0 / nz) * (2 * kPi / nphi);
    EXPECT_NEAR(integral, 1.0, 2e-3);
}

TEST(EnvMapEmitter, PowerAndSplit) {
    EnvMapFixture f;
    const auto e = f.emitter();
    // pi R^2 times the integral of the map over the sphere (exact per pixel band).
    double integral = 0;
    for (int y = 0; y < f.map.height; ++y)
        for (int x = 0; x < f.map.width; ++x)
            integral += f.map.get(x, y).luminance() * f.scale * (2 * kPi / f.map.width) *
                        (std::cos(kPi * y / f.map.height) - std::cos(kPi * (y + 1) / f.map.height));
    EXPECT_NEAR(e->power().luminance(), kPi * 4.0 * integral, 1e-9 * integral);
    expectLightTracingPower(*e, 400000);
    expectDirectMatchesSplit(*e, {Vec3(0.2, 0.8, -0.3), Vec3(0, 1, 0)});
}

TEST(EnvMapEmitter, BadParameters) {
    EnvMapFixture f;
    Properties p = props(ObjectKind::Emitter, "envmap");
    p.set("filename", Properties::Type::String, std::string("missing.exr"), kLoc);
    expectBadParameter(p, "filename", f.ctx);
    for (const double gamma : {-2.0, -0.5}) {
        p = f.properties();
        setFloat(p, "gamma", gamma);
        expectBadParameter(p, "gamma", f.ctx);
    }
    for (const double scale : {0.0, -1.0}) {
        p = props(ObjectKind::Emitter, "envmap");
        p.set("filename", Properties::Type::String, std::string("map.exr"), kLoc);
        setFloat(p, "scale", scale);
        expectBadParameter(p, "scale", f.ctx);
    }
    p = props(ObjectKind::Emitter, "envmap");
    p.set("filename", Properties::Type::String, std::string("map.exr"), kLoc);
    setTransform(p, "toWorld", Transform::scale(Vec3(1, 2, 1)));
    expectBadParameter(p, "toWorld", f.ctx);

    Bitmap black(8, 4);
    writeEXR(f.dir + "/black.exr", black);
    Bitmap negative = testMap();
    negative.set(3, 3, Spectrum(-1.0, 0.0, 0.0));
    writeEXR(f.dir + "/negative.exr", negative);
    for (const char *name : {"black.exr", "negative.exr"}) {
        p = props(ObjectKind::Emitter, "envmap");
        p.set("filename", Properties::Type::String, std::string(name), kLoc);
        expectBadParameter(p, "filename", f.ctx);
    }
}

// ---- bad parameters of the other emitters ----

TEST(Emitters, BadParameters) {
    Properties p = props(ObjectKind::Emitter, "area");
    setSpectrum(p, "radiance", Spectrum(1.0, -1.0, 1.0));
    expectBadParameter(p, "radiance");
    for (const double w : {0.0, -1.0, std::nan("")}) {
        p = props(ObjectKind::Emitter, "point");
        setFloat(p, "samplingWeight", w);
        expectBadParameter(p, "samplingWeight");
    }
    p = props(ObjectKind::Emitter, "point");
    p.set("position", Properties::Type::Point, Vec3(1, 2, 3), kLoc);
    setTransform(p, "toWorld", Transform());
    expectBadParameter(p, "position");
    p = props(ObjectKind::Emitter, "point");
    setFloat(p, "intensity", std::nan(""));
    expectBadParameter(p, "intensity");
    for (const double cutoff : {0.0, -5.0, 190.0}) {
        p = props(ObjectKind::Emitter, "spot");
        setFloat(p, "cutoffAngle", cutoff);
        expectBadParameter(p, "cutoffAngle");
    }
    p = props(ObjectKind::Emitter, "spot");
    setFloat(p, "cutoffAngle", 20);
    setFloat(p, "beamWidth", 25);
    expectBadParameter(p, "beamWidth");
    p = props(ObjectKind::Emitter, "spot");
    setTransform(p, "toWorld", Transform::scale(Vec3(1, 1, 3)));
    expectBadParameter(p, "toWorld");
    p = props(ObjectKind::Emitter, "directional");
    p.set("direction", Properties::Type::Vector, Vec3(0.0), kLoc);
    expectBadParameter(p, "direction");
    p = props(ObjectKind::Emitter, "constant");
    setSpectrum(p, "radiance", Spectrum(-1.0));
    expectBadParameter(p, "radiance");
}

}  // namespace
}  // namespace pf::test
