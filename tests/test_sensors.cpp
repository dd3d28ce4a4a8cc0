// Sensors: raster mapping (round trips through every fovAxis, crop windows, handedness), the importance
// normalization that light tracing relies on (Monte Carlo over scene points must give every pixel the
// same share of a unit total), chi-square tests of direction sampling, clip planes, thin-lens aperture
// hits, and bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "image/film.h"
#include "scene/plugins.h"
#include "scene/sampler_settings.h"
#include "sensor/projective.h"
#include "support/chi2.h"

namespace pf::test {
namespace {

const SourceLocation kLoc{"test.xml", 1};

struct SensorSpec {
    std::string type = "perspective";
    int width = 64, height = 48;
    int cropX = 0, cropY = 0, cropW = 0, cropH = 0;  // cropW = 0: no crop
    std::string fovAxis;                             // empty: not given
    double fov = 50;
    double apertureRadius = 0.1, focusDistance = 3;  // thinlens only
    Transform toWorld = Transform::lookAt(Vec3(1, 2, 3), Vec3(1.5, 2.2, 8), Vec3(0, 1, 0));
};

std::shared_ptr<Object> makeFilm(const SensorSpec &s) {
    Properties p(ObjectKind::Film, "hdrfilm", kLoc);
    p.set("width", Properties::Type::Integer, int64_t(s.width), kLoc);
    p.set("height", Properties::Type::Integer, int64_t(s.height), kLoc);
    if (s.cropW > 0) {
        p.set("cropOffsetX", Properties::Type::Integer, int64_t(s.cropX), kLoc);
        p.set("cropOffsetY", Properties::Type::Integer, int64_t(s.cropY), kLoc);
        p.set("cropWidth", Properties::Type::Integer, int64_t(s.cropW), kLoc);
        p.set("cropHeight", Properties::Type::Integer, int64_t(s.cropH), kLoc);
    }
    return (*findPlugin(ObjectKind::Film, "hdrfilm"))(p, LoadContext{});
}

Properties sensorProps(const SensorSpec &s) {
    Properties p(ObjectKind::Sensor, s.type, kLoc);
    p.set("fov", Properties::Type::Float, s.fov, kLoc);
    if (!s.fovAxis.empty()) p.set("fovAxis", Properties::Type::String, s.fovAxis, kLoc);
    p.set("toWorld", Properties::Type::Transform, s.toWorld, kLoc);
    if (s.type == "thinlens") {
        p.set("apertureRadius", Properties::Type::Float, s.apertureRadius, kLoc);
        p.set("focusDistance", Properties::Type::Float, s.focusDistance, kLoc);
    }
    p.addChild({"", ObjectKind::Film, makeFilm(s), kLoc});
    return p;
}

std::shared_ptr<ProjectiveCamera> makeSensor(const Properties &p) {
    auto object = (*findPlugin(ObjectKind::Sensor, p.pluginName()))(p, LoadContext{});
    p.checkAllUsed();
    return std::dynamic_pointer_cast<ProjectiveCamera>(object);
}
std::shared_ptr<ProjectiveCamera> makeSensor(const SensorSpec &s) { return makeSensor(sensorProps(s)); }

// Expects construction to fail with a SceneError whose message names `param`.
void expectBadParameter(const Properties &p, const std::string &param) {
    try {
        makeSensor(p);
        ADD_FAILURE() << "no error for bad '" << param << "'";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("'" + param + "'"), std::string::npos) << e.what();
    }
}

std::vector<SensorSpec> allVariants() {
    std::vector<SensorSpec> specs;
    for (const char *type : {"perspective", "thinlens"})
        for (const char *axis : {"x", "y", "diagonal", "smaller", "larger"})
            for (bool crop : {false, true})
                for (bool portrait : {false, true}) {
                    SensorSpec s;
                    s.type = type;
                    s.fovAxis = axis;
                    if (portrait) std::swap(s.width, s.height);
                    if (crop) {
                        s.cropX = 5, s.cropY = 7, s.cropW = 20, s.cropH = 13;
                    }
                    specs.push_back(s);
                }
    return specs;
}

TEST(Sensors, RasterRoundTrip) {
    PCG32 rng(7, 1);
    for (const SensorSpec &s : allVariants()) {
        const auto sensor = makeSensor(s);
        const Film &film = sensor->film();
        for (int i = 0; i < 200; ++i) {
            const Vec2 raster(rng.nextDouble() * film.cropWidth(), rng.nextDouble() * film.cropHeight());
            Ray ray;
            const Spectrum w = sensor->sampleRay(ray, raster, {rng.nextDouble(), rng.nextDouble()});
            EXPECT_EQ(w, Spectrum(1.0));
            Vec2 back;
            ASSERT_TRUE(sensor->rasterPosition(ray.o, ray.d, back)) << s.type << " " << s.fovAxis;
            EXPECT_NEAR(back.x, raster.x, 1e-8) << s.type << " " << s.fovAxis;
            EXPECT_NEAR(back.y, raster.y, 1e-8) << s.type << " " << s.fovAxis;
        }
    }
}

// The horizontal field of view that each fovAxis implies (Mitsuba's setXFov / setYFov / setDiagonalFov).
TEST(Sensors, FovAxes) {
    for (bool portrait : {false, true}) {
        SensorSpec s;
        if (portrait) std::swap(s.width, s.height);
        const double aspect = double(s.width) / s.height, t = std::tan(degToRad(s.fov / 2));
        const double xFromY = radToDeg(2 * std::atan(t * aspect));
        const double xFromDiagonal = radToDeg(2 * std::atan(t / std::sqrt(1 + 1 / (aspect * aspect))));
        const auto xFov = [&](const char *axis) {
            s.fovAxis = axis;
            return makeSensor(s)->xFov();
        };
        EXPECT_NEAR(xFov("x"), s.fov, 1e-9);
        EXPECT_NEAR(xFov("y"), xFromY, 1e-9);
        EXPECT_NEAR(xFov("diagonal"), xFromDiagonal, 1e-9);
        EXPECT_NEAR(xFov("smaller"), portrait ? s.fov : xFromY, 1e-9);
        EXPECT_NEAR(xFov("larger"), portrait ? xFromY : s.fov, 1e-9);
        EXPECT_NEAR(xFov("X"), s.fov, 1e-9);  // Mitsuba lower-cases fovAxis
    }
}

// Without fov, focalLength (default 50mm, 35 mm film equivalent) gives the diagonal field of view.
TEST(Sensors, FocalLength) {
    for (const char *focal : {"", "50mm", "24mm", "85"}) {
        SensorSpec s;
        Properties p(ObjectKind::Sensor, "perspective", kLoc);
        if (*focal) p.set("focalLength", Properties::Type::String, std::string(focal), kLoc);
        p.addChild({"", ObjectKind::Film, makeFilm(s), kLoc});
        const double mm = *focal ? std::atof(focal) : 50.0;
        const double aspect = double(s.width) / s.height;
        const double halfDiagonal = std::sqrt(36.0 * 36 + 24 * 24) / (2 * mm);
        const double expected = radToDeg(2 * std::atan(halfDiagonal / std::sqrt(1 + 1 / (aspect * aspect))));
        EXPECT_NEAR(makeSensor(p)->xFov(), expected, 1e-9) << focal;
    }
}

// Mitsuba's handedness: with a lookat transform, what lies to the camera's left (local +x = up x dir) is on
// the image's left, and what is above is at the top.
TEST(Sensors, Handedness) {
    for (const char *type : {"perspective", "thinlens"}) {
        SensorSpec s;
        s.type = type;
        s.apertureRadius = 1e-3;
        s.toWorld = Transform::lookAt(Vec3(0, 0, 0), Vec3(0, 0, 1), Vec3(0, 1, 0));
        const auto sensor = makeSensor(s);
        const Vec3 left = cross(Vec3(0, 1, 0), Vec3(0, 0, 1));  // camera-local +x
        EXPECT_EQ(left, Vec3(1, 0, 0));
        DirectSample ds(Vec3(0.3, 0, 3), Vec3(0, 0, -1));
        ASSERT_FALSE(sensor->sampleDirect(ds, {0.5, 0.5}).isBlack());
        EXPECT_LT(ds.uv.x, s.width / 2.0);
        EXPECT_NEAR(ds.uv.y, s.height / 2.0, 0.1);
        ds = DirectSample(Vec3(0, 0.3, 3), Vec3(0, 0, -1));
        ASSERT_FALSE(sensor->sampleDirect(ds, {0.5, 0.5}).isBlack());
        EXPECT_LT(ds.uv.y, s.height / 2.0);
        EXPECT_NEAR(ds.uv.x, s.width / 2.0, 0.1);
        // sampleRay agrees: raster (0, 0) looks up and to the left.
        Ray ray;
        sensor->sampleRay(ray, {0, 0}, {0.5, 0.5});
        EXPECT_GT(ray.d.x, 0);
        EXPECT_GT(ray.d.y, 0);
    }
}

// The importance normalization seen by light tracing. Scene points are drawn uniformly on a large plane in
// front of the camera (covering the whole view). For every point, sampleDirect gives the importance
// arriving there per unit density; times the cosine at the point and divided by the area density, its
// mean is the integral of We * cos over the image, which is 1, and every pixel receives 1 / pixels of it.
// The same holds for the thin lens, whose aperture is sampled too.
TEST(Sensors, ImportanceIntegratesToOnePerImage) {
    for (const char *type : {"perspective", "thinlens"})
        for (bool crop : {false, true}) {
            SensorSpec s;
            s.type = type;
            s.width = 8, s.height = 6, s.fov = 60;
            if (crop) s.cropX = 2, s.cropY = 1, s.cropW = 4, s.cropH = 3;
            s.apertureRadius = 0.2, s.focusDistance = 2.5;  // focused in front of the plane: blur
            const auto sensor = makeSensor(s);
            const Film &film = sensor->film();
            const int pixels = film.cropWidth() * film.cropHeight();
            const double depth = 4, half = 6;  // plane z = depth, |x|, |y| <= half in camera space
            const double planeArea = 4 * half * half;
            const Vec3 planeNormal = normalize(s.toWorld.vector(Vec3(0, 0, -1)));
            std::vector<double> sum(pixels, 0.0), sumSq(pixels, 0.0);
            PCG32 rng(11, 3);
            const int n = 400000;
            for (int i = 0; i < n; ++i) {
                const Vec3 local((2 * rng.nextDouble() - 1) * half, (2 * rng.nextDouble() - 1) * half, depth);
                DirectSample ds(s.toWorld.point(local), planeNormal);
                const Spectrum w = sensor->sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()});
                if (w.isBlack()) continue;
                ASSERT_GE(ds.uv.x, 0);
                ASSERT_LE(ds.uv.x, film.cropWidth());
                const int px = std::min(int(ds.uv.x), film.cropWidth() - 1);
                const int py = std::min(int(ds.uv.y), film.cropHeight() - 1);
                const double v = w.r * absDot(ds.d, planeNormal) * planeArea;
                sum[py * film.cropWidth() + px] += v;
                sumSq[py * film.cropWidth() + px] += v * v;
            }
            double total = 0, totalVar = 0;
            for (int j = 0; j < pixels; ++j) {
                const double mean = sum[j] / n, var = (sumSq[j] / n - mean * mean) / n;
                EXPECT_NEAR(mean, 1.0 / pixels, 4 * std::sqrt(var)) << type << " pixel " << j;
                total += mean;
                totalVar += var;
            }
            EXPECT_NEAR(total, 1.0, 4 * std::sqrt(totalVar)) << type;
            EXPECT_LT(std::sqrt(totalVar), 0.01);  // the test has the power to see a 4% error
        }
}

// sampleDirect agrees with the position / direction split that BDPT evaluates:
// value = evalPosition * evalDirection / (dist^2 * pdfPosition), pdfDirect reproduces the density, and a
// ray from the reference point to the sampled aperture point hits the lens there (thin lens).
TEST(Sensors, DirectSamplingMatchesPositionDirectionSplit) {
    for (const char *type : {"perspective", "thinlens"}) {
        SensorSpec s;
        s.type = type;
        const auto sensor = makeSensor(s);
        EXPECT_EQ(sensor->deltaAperture(), std::string(type) == "perspective");
        PCG32 rng(5, 9);
        int tested = 0;
        for (int i = 0; i < 2000; ++i) {
            const Vec3 local((2 * rng.nextDouble() - 1) * 2, (2 * rng.nextDouble() - 1) * 2, 1 + 4 * rng.nextDouble());
            DirectSample ds(s.toWorld.point(local), Vec3(0.0));
            const Spectrum w = sensor->sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()});
            if (w.isBlack()) continue;
            ++tested;
            PositionSample ps;
            ps.p = ds.p;
            ps.n = ds.n;
            ps.measure = sensor->deltaAperture() ? Measure::Discrete : Measure::Area;
            DirectionSample dir;
            dir.d = -ds.d;
            const double expected = sensor->evalPosition(ps).r * sensor->evalDirection(dir, ps).r /
                                    (ds.dist * ds.dist * sensor->pdfPosition(ps));
            EXPECT_NEAR(w.r, expected, 1e-9 * expected);
            EXPECT_NEAR(sensor->pdfDirect(ds), ds.pdf, 1e-9 * ds.pdf);
            Vec2 raster;
            ASSERT_TRUE(sensor->rasterPosition(ds.p, -ds.d, raster));
            EXPECT_NEAR(raster.x, ds.uv.x, 1e-8);
            EXPECT_NEAR(raster.y, ds.uv.y, 1e-8);
            PositionSample hit;
            double t = 0;
            const bool hits = sensor->intersectAperture(Ray(ds.ref, ds.d, 0, ds.dist * 1.001), hit, t);
            EXPECT_EQ(hits, !sensor->deltaAperture());
            if (hits) {
                EXPECT_NEAR(t, ds.dist, 1e-9 * ds.dist);
                EXPECT_NEAR((hit.p - ds.p).length(), 0, 1e-9);
                EXPECT_NEAR(hit.uv.x, ds.uv.x, 1e-8);
                EXPECT_NEAR(hit.pdf, sensor->pdfPosition(hit), 0);
            }
        }
        EXPECT_GT(tested, 500);
    }
}

// Camera direction sampling: sampleDirection through uniform raster positions has density pdfDirection.
// A wide field of view and many theta bins spread the frustum over many cells; the density jumps to zero
// at the frustum's edges, so the cells that the edges cut are integrated on a finer grid than usual.
TEST(Sensors, DirectionSamplingChiSquare) {
    for (const char *type : {"perspective", "thinlens"}) {
        SensorSpec s;
        s.type = type;
        s.fov = 120;
        s.apertureRadius = 0.5, s.focusDistance = 1;
        s.cropX = 3, s.cropY = 4, s.cropW = 50, s.cropH = 30;
        s.toWorld = Transform::translate(Vec3(0, 1, 0)) * Transform::rotate(Vec3(1, 0, 0), 30);
        const auto sensor = makeSensor(s);
        const Film &film = sensor->film();
        PositionSample ps;
        sensor->samplePosition(ps, {0.8, 0.3});  // an off-centre point of the lens
        Chi2Options opt;
        opt.thetaBins = 80;
        opt.phiBins = 40;
        opt.integrationRes = 48;
        opt.testCount = 2;
        const auto r = chi2Sphere(
            [&](PCG32 &rng, Vec3 &d) {
                DirectionSample ds;
                PositionSample p = ps;
                const Vec2 raster(rng.nextDouble() * film.cropWidth(), rng.nextDouble() * film.cropHeight());
                const Spectrum w = sensor->sampleDirection(ds, p, raster);
                EXPECT_EQ(w, Spectrum(1.0));
                EXPECT_EQ(p.uv.x, raster.x);
                d = ds.d;
                return true;
            },
            [&](const Vec3 &d) {
                DirectionSample ds;
                ds.d = d;
                return sensor->pdfDirection(ds, ps);
            },
            opt);
        EXPECT_TRUE(r.passed) << type << ": " << r.report;
        EXPECT_NEAR(r.integratedMass, 1.0, 2e-3) << type;
    }
}

// Rays start at the near clip plane and end at the far one (planes of constant camera depth), and
// points outside [nearClip, farClip] receive no importance.
TEST(Sensors, ClipPlanes) {
    for (const char *type : {"perspective", "thinlens"}) {
        SensorSpec s;
        s.type = type;
        Properties p = sensorProps(s);
        p.set("nearClip", Properties::Type::Float, 0.5, kLoc);
        p.set("farClip", Properties::Type::Float, 7.0, kLoc);
        const auto sensor = makeSensor(p);
        EXPECT_EQ(sensor->nearClip(), 0.5);
        EXPECT_EQ(sensor->farClip(), 7.0);
        const Transform toLocal = s.toWorld.inverse();
        Ray ray;
        sensor->sampleRay(ray, {3.3, 40.1}, {0.2, 0.9});
        EXPECT_NEAR(toLocal.point(ray(ray.tmin)).z, 0.5, 1e-9);
        EXPECT_NEAR(toLocal.point(ray(ray.tmax)).z, 7.0, 1e-9);
        for (const double z : {0.45, 0.55, 6.9, 7.1}) {
            DirectSample ds(s.toWorld.point(Vec3(0.01, 0.02, z)), Vec3(0.0));
            const bool inside = z > 0.5 && z < 7.0;
            EXPECT_EQ(sensor->sampleDirect(ds, {0.5, 0.5}).isBlack(), !inside) << type << " z = " << z;
        }
    }
}

// Positions: the pinhole is a Discrete point; the thin lens samples its disk uniformly.
TEST(Sensors, AperturePositions) {
    SensorSpec s;
    auto pinhole = makeSensor(s);
    PositionSample ps;
    EXPECT_EQ(pinhole->samplePosition(ps, {0.3, 0.7}), Spectrum(1.0));
    EXPECT_EQ(ps.measure, Measure::Discrete);
    EXPECT_EQ(ps.pdf, 1.0);
    EXPECT_NEAR((ps.p - s.toWorld.point(Vec3(0.0))).length(), 0, 1e-12);
    Ray ray(Vec3(1, 2, 5), Vec3(0, 0, -1));
    double t;
    EXPECT_FALSE(pinhole->intersectAperture(ray, ps, t));

    s.type = "thinlens";
    auto lens = makeSensor(s);
    PCG32 rng(3, 3);
    for (int i = 0; i < 1000; ++i) {
        EXPECT_EQ(lens->samplePosition(ps, {rng.nextDouble(), rng.nextDouble()}), Spectrum(1.0));
        EXPECT_EQ(ps.measure, Measure::Area);
        EXPECT_NEAR(ps.pdf, 1.0 / (kPi * s.apertureRadius * s.apertureRadius), 1e-9);
        const Vec3 local = s.toWorld.inverse().point(ps.p);
        EXPECT_NEAR(local.z, 0, 1e-12);
        EXPECT_LE(std::hypot(local.x, local.y), s.apertureRadius + 1e-12);
    }
}

// Mitsuba's defaults: an hdrfilm of 768 x 576 and 4 samples per pixel; a nested sampler sets the count.
TEST(Sensors, DefaultFilmAndSampler) {
    Properties p(ObjectKind::Sensor, "perspective", kLoc);
    auto sensor = makeSensor(p);
    EXPECT_EQ(sensor->film().width(), 768);
    EXPECT_EQ(sensor->film().height(), 576);
    EXPECT_EQ(sensor->sampleCount(), 4);

    Properties q(ObjectKind::Sensor, "perspective", kLoc);
    q.addChild({"", ObjectKind::Sampler, std::make_shared<SamplerSettings>(64, SampleSequence{}), kLoc});
    EXPECT_EQ(makeSensor(q)->sampleCount(), 64);
}

TEST(Sensors, BadParameters) {
    for (const char *type : {"perspective", "thinlens"}) {
        SensorSpec s;
        s.type = type;
        for (double fov : {0.0, -10.0, 180.0, 200.0, std::nan("")}) {
            s.fov = fov;
            expectBadParameter(sensorProps(s), "fov");
        }
        s.fov = 50;
        s.fovAxis = "w";
        expectBadParameter(sensorProps(s), "fovAxis");
        s.fovAxis = "";
        s.toWorld = Transform::scale(Vec3(2, 1, 1));
        expectBadParameter(sensorProps(s), "toWorld");
        s.toWorld = Transform();
        Properties p = sensorProps(s);
        p.set("nearClip", Properties::Type::Float, 0.0, kLoc);
        expectBadParameter(p, "nearClip");
        p = sensorProps(s);
        p.set("farClip", Properties::Type::Float, 1e-3, kLoc);
        expectBadParameter(p, "farClip");
        p = sensorProps(s);
        p.set("focalLength", Properties::Type::String, std::string("35mm"), kLoc);
        expectBadParameter(p, "focalLength");
    }
    Properties p(ObjectKind::Sensor, "perspective", kLoc);
    p.set("focalLength", Properties::Type::String, std::string("wide"), kLoc);
    expectBadParameter(p, "focalLength");
    SensorSpec s;
    s.type = "thinlens";
    for (double r : {-0.1, 0.0, std::nan("")}) {
        s.apertureRadius = r;
        expectBadParameter(sensorProps(s), "apertureRadius");
    }
    s.apertureRadius = 0.1;
    s.focusDistance = -1;
    expectBadParameter(sensorProps(s), "focusDistance");
}

}  // namespace
}  // namespace pf::test
