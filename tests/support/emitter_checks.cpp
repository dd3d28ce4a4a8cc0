#include "support/emitter_checks.h"

#include <gtest/gtest.h>

#include <cmath>

#include "scene/plugins.h"

namespace pf::test {

Chi2Options emitterChi2Options(int testCount, int thetaBins, int phiBins, int integrationRes) {
    Chi2Options o;
    o.thetaBins = thetaBins;
    o.phiBins = phiBins;
    o.integrationRes = integrationRes;
    o.testCount = testCount;
    return o;
}

Properties props(ObjectKind kind, const std::string &plugin) { return Properties(kind, plugin, kEmitterTestLoc); }
void setFloat(Properties &p, const std::string &name, double v) {
    p.set(name, Properties::Type::Float, v, kEmitterTestLoc);
}
void setSpectrum(Properties &p, const std::string &name, const Spectrum &v) {
    p.set(name, Properties::Type::Spectrum, v, kEmitterTestLoc);
}
void setTransform(Properties &p, const std::string &name, const Transform &t) {
    p.set(name, Properties::Type::Transform, t, kEmitterTestLoc);
}

std::shared_ptr<Emitter> makeEmitter(const Properties &p, const LoadContext &ctx) {
    auto object = (*findPlugin(ObjectKind::Emitter, p.pluginName()))(p, ctx);
    p.checkAllUsed();
    return std::dynamic_pointer_cast<Emitter>(object);
}

void expectBadParameter(const Properties &p, const std::string &param, const LoadContext &ctx) {
    try {
        makeEmitter(p, ctx);
        ADD_FAILURE() << "no error for bad '" << param << "'";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("'" + param + "'"), std::string::npos) << e.what();
    }
}

Chi2Result emissionChi2(const Emitter &e, const PositionSample &ps, const Chi2Options &opt) {
    return chi2Sphere(
        [&](PCG32 &rng, Vec3 &d) {
            DirectionSample ds;
            const Spectrum w = e.sampleDirection(ds, ps, {rng.nextDouble(), rng.nextDouble()});
            EXPECT_TRUE(w.isValid());
            if (!(ds.pdf > 0)) return false;
            // The weight is evalDirection / pdf.
            const Spectrum expected = e.evalDirection(ds, ps) / ds.pdf;
            EXPECT_NEAR(w.g, expected.g, 1e-9 * std::max(1.0, expected.g));
            EXPECT_NEAR(e.pdfDirection(ds, ps), ds.pdf, 1e-9 * ds.pdf);
            d = ds.d;
            return true;
        },
        [&](const Vec3 &d) {
            DirectionSample ds;
            ds.d = d;
            return e.pdfDirection(ds, ps);
        },
        opt);
}

Chi2Result directChi2(const Emitter &e, const Vec3 &ref,
                      const std::function<bool(const Vec3 &, const Vec3 &, DirectSample &)> &hit,
                      const Chi2Options &opt) {
    return chi2Sphere(
        [&](PCG32 &rng, Vec3 &d) {
            DirectSample ds(ref, Vec3(0.0));
            e.sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()});
            if (!(ds.pdf > 0)) return false;
            d = ds.d;
            return true;
        },
        [&](const Vec3 &d) {
            DirectSample ds(ref, Vec3(0.0));
            if (!hit(ref, d, ds)) return 0.0;
            ds.measure = Measure::SolidAngle;
            return e.pdfDirect(ds);
        },
        opt);
}

void expectLightTracingPower(const Emitter &e, int n) {
    PCG32 rng(17, 5);
    double sum = 0, sumSq = 0;
    for (int i = 0; i < n; ++i) {
        PositionSample ps;
        const Spectrum wp = e.samplePosition(ps, {rng.nextDouble(), rng.nextDouble()});
        DirectionSample ds;
        const Spectrum wd = e.sampleDirection(ds, ps, {rng.nextDouble(), rng.nextDouble()});
        const double v = (wp * wd).luminance();
        sum += v;
        sumSq += v * v;
    }
    const double mean = sum / n, stderr_ = std::sqrt(std::max(0.0, sumSq / n - mean * mean) / n);
    const double power = e.power().luminance();
    EXPECT_NEAR(mean, power, 4 * stderr_ + 1e-9 * power) << "standard error " << stderr_;
    EXPECT_LT(stderr_, 0.01 * power);  // enough samples to see a 4% error
}

void expectDirectMatchesSplit(const Emitter &e, const std::vector<Vec3> &refs) {
    PCG32 rng(23, 1);
    int nonZero = 0;
    for (const Vec3 &ref : refs)
        for (int i = 0; i < 200; ++i) {
            DirectSample ds(ref, Vec3(0.0));
            const Spectrum value = e.sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()});
            if (value.isBlack()) continue;
            ++nonZero;
            EXPECT_EQ(ds.object, &e);
            EXPECT_NEAR(ds.d.length(), 1.0, 1e-12);
            EXPECT_NEAR(e.pdfDirect(ds), ds.pdf, 1e-9 * ds.pdf);
            PositionSample ps;
            ps.p = ds.p;
            ps.n = ds.n;
            ps.measure = ds.measure == Measure::Discrete ? Measure::Discrete : Measure::Area;
            DirectionSample dir;
            dir.d = -ds.d;
            const Spectrum split = e.evalPosition(ps) * e.evalDirection(dir, ps);
            const Spectrum expected =
                ds.measure == Measure::Discrete ? split / (ds.dist * ds.dist) : split / (absDot(ds.n, ds.d) * ds.pdf);
            EXPECT_NEAR(value.r, expected.r, 1e-9 * expected.r);
            EXPECT_NEAR(value.b, expected.b, 1e-9 * expected.b);
        }
    EXPECT_GT(nonZero, 100);
}

bool environmentHit(const Emitter &e, const Vec3 &o, const Vec3 &d, DirectSample &ds) {
    return e.fillDirectSample(ds, Ray(o, d));
}

}  // namespace pf::test
