// Participating media and phase functions in isolation: chi-square tests of phase-function and
// free-flight sampling against their densities, the golden HG quantile of ALGORITHMS.md §9.2, the
// normalization of the distance densities that BDPT relies on, the unbiasedness of the chromatic
// ("balance") weights, Mitsuba's parameter conventions, and the rejection of bad parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "core/frame.h"
#include "medium/media.h"
#include "scene/properties.h"
#include "support/chi2.h"

namespace pf::test {
namespace {

constexpr int kSphereTests = 6;  // chi2Sphere runs in this file (isotropic + five g), for the Sidak correction

Properties makeProps(ObjectKind kind, const std::string &plugin) {
    return Properties(kind, plugin, SourceLocation{"test.xml", 1});
}
void setFloat(Properties &p, const std::string &name, double v) {
    p.set(name, Properties::Type::Float, v, SourceLocation{"test.xml", 2});
}
void setSpectrum(Properties &p, const std::string &name, const Spectrum &s) {
    p.set(name, Properties::Type::Spectrum, s, SourceLocation{"test.xml", 3});
}
void setString(Properties &p, const std::string &name, const std::string &s) {
    p.set(name, Properties::Type::String, s, SourceLocation{"test.xml", 4});
}

// Plugins are built through the same tables the loader uses.
std::shared_ptr<Object> build(const PluginTable &table, const std::string &type, const Properties &props) {
    for (const auto &[name, factory] : table)
        if (name == type) return factory(props, LoadContext{});
    ADD_FAILURE() << "no plugin '" << type << "'";
    return nullptr;
}

std::shared_ptr<PhaseFunction> makeHG(double g) {
    Properties p = makeProps(ObjectKind::Phase, "hg");
    setFloat(p, "g", g);
    return std::dynamic_pointer_cast<PhaseFunction>(build(phasePlugins(), "hg", p));
}

std::shared_ptr<Medium> makeMedium(const Properties &p) {
    return std::dynamic_pointer_cast<Medium>(build(mediumPlugins(), "homogeneous", p));
}

std::shared_ptr<Medium> makeMedium(const Spectrum &sigmaS, const Spectrum &sigmaA) {
    Properties p = makeProps(ObjectKind::Medium, "homogeneous");
    setSpectrum(p, "sigmaS", sigmaS);
    setSpectrum(p, "sigmaA", sigmaA);
    return makeMedium(p);
}

// An incident direction (pointing away from the scattering point) that is not aligned with any axis,
// so that the frame built around -wi is exercised.
const Vec3 kWi = normalize(Vec3(0.3, -0.5, 0.8));

// Composite Simpson rule on [a, b] with n (even) intervals.
double simpson(const std::function<double(double)> &f, double a, double b, int n) {
    const double h = (b - a) / n;
    double sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
    return sum * h / 3.0;
}

// The phase function's value for scattering-angle cosine mu (angle between -wi and wo).
double phaseAt(const PhaseFunction &phase, double mu) {
    const Frame frame(-kWi);
    return phase.eval(kWi, frame.toWorld(Vec3(safeSqrt(1 - mu * mu), 0, mu)));
}

void expectPhaseMatchesItsPdf(const PhaseFunction &phase, const char *what) {
    Chi2Options opt;
    opt.testCount = kSphereTests;
    opt.integrationRes = 16;  // the HG lobes are peaked; integrate each bin finely enough
    bool consistent = true;
    const auto r = chi2Sphere(
        [&](PCG32 &rng, Vec3 &d) {
            double pdf = 0;
            const Vec2 u(rng.nextDouble(), rng.nextDouble());
            const double weight = phase.sample(kWi, d, pdf, u);
            // Exact importance sampling: weight 1, and the reported density is the one pdf() gives.
            if (std::abs(weight - 1.0) > 1e-12 || std::abs(pdf - phase.pdf(kWi, d)) > 1e-9 * pdf) consistent = false;
            return true;
        },
        [&](const Vec3 &d) { return phase.pdf(kWi, d); }, opt);
    EXPECT_TRUE(r.passed) << what << ": " << r.report;
    EXPECT_NEAR(r.integratedMass, 1.0, 2e-3) << what;
    EXPECT_TRUE(consistent) << what << ": sample() weight or density disagrees with pdf()";
}

TEST(PhaseFunction, IsotropicSamplingMatchesPdf) {
    const auto iso = makeIsotropicPhase();
    expectPhaseMatchesItsPdf(*iso, "isotropic");
    EXPECT_DOUBLE_EQ(iso->eval(kWi, Vec3(0, 0, 1)), kInvFourPi);
    EXPECT_EQ(iso->meanCosine(), 0.0);
}

TEST(PhaseFunction, HenyeyGreensteinSamplingMatchesPdf) {
    for (double g : {-0.7, -0.3, 0.0, 0.4, 0.75}) {
        const auto hg = makeHG(g);
        expectPhaseMatchesItsPdf(*hg, ("hg g = " + std::to_string(g)).c_str());
    }
}

// Normalization, mean cosine, direction convention (g > 0 scatters forward, i.e. towards -wi) and
// reciprocity, by quadrature over the scattering angle.
TEST(PhaseFunction, HenyeyGreensteinMomentsAndConvention) {
    for (double g : {-0.8, -0.2, 0.0, 0.5, 0.9}) {
        const auto hg = makeHG(g);
        const double mass = simpson([&](double mu) { return 2 * kPi * phaseAt(*hg, mu); }, -1, 1, 20000);
        const double mean = simpson([&](double mu) { return 2 * kPi * mu * phaseAt(*hg, mu); }, -1, 1, 20000);
        EXPECT_NEAR(mass, 1.0, 1e-6) << "g = " << g;
        EXPECT_NEAR(mean, g, 1e-6) << "g = " << g;
        EXPECT_EQ(hg->meanCosine(), g);
        const Vec3 wo = normalize(Vec3(-0.6, 0.2, 0.1));
        EXPECT_NEAR(hg->eval(kWi, wo), hg->eval(wo, kWi), 1e-14);
        if (g > 0) {
            EXPECT_GT(hg->eval(kWi, -kWi), hg->eval(kWi, kWi)) << "g > 0 must favour forward scattering";
        }
    }
}

// ALGORITHMS.md §6.6 / §9.2 [CHK]: for g = 0.8 the median scattering angle has cos theta_q = 0.944. The
// quantile formula, the sampling inversion and direct quadrature of the density must all agree.
TEST(PhaseFunction, HenyeyGreensteinQuantileGoldenValue) {
    EXPECT_NEAR(hgQuantileCosine(0.8, 0.5), 0.944, 1e-12);
    EXPECT_NEAR(std::acos(hgQuantileCosine(0.8, 0.5)) * 180 / kPi, 19.3, 0.05);

    const auto hg = makeHG(0.8);
    Vec3 wo;
    double pdf = 0;
    hg->sample(kWi, wo, pdf, Vec2(0.5, 0.3));
    EXPECT_NEAR(dot(wo, -kWi), 0.944, 1e-12) << "u = 0.5 must give the median scattering angle";

    for (double g : {0.8, 0.3, -0.6}) {
        const auto phase = makeHG(g);
        for (double q : {0.1, 0.5, 0.9}) {
            const double muQ = hgQuantileCosine(g, q);
            // Probability of scattering within theta_q of the forward (g >= 0) or backward (g < 0) direction.
            const double inside =
                g >= 0 ? simpson([&](double mu) { return 2 * kPi * phaseAt(*phase, mu); }, muQ, 1, 20000)
                       : simpson([&](double mu) { return 2 * kPi * phaseAt(*phase, mu); }, -1, -muQ, 20000);
            EXPECT_NEAR(inside, q, 1e-7) << "g = " << g << ", q = " << q;
            EXPECT_NEAR(hgSampleCosine(std::abs(g), 1 - q), muQ, 1e-12) << "g = " << g << ", q = " << q;
        }
    }
}

// The inversion is written without a division by g, so tiny g gives the isotropic 2u - 1, not noise.
TEST(PhaseFunction, HenyeyGreensteinSamplingIsStableForTinyG) {
    for (double u : {0.0, 0.1, 0.5, 0.77, 1.0}) {
        EXPECT_NEAR(hgSampleCosine(1e-12, u), 2 * u - 1, 1e-11);
        EXPECT_NEAR(hgSampleCosine(0.0, u), 2 * u - 1, 1e-15);
    }
    EXPECT_NEAR(hgSampleCosine(0.9, 0.0), -1.0, 1e-12);
    EXPECT_NEAR(hgSampleCosine(-0.9, 1.0), 1.0, 1e-12);
}

// Closed-form channel-averaged densities of the balance strategy with sampling weight w.
double successDensity(const Spectrum &sigmaT, double w, double t) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += sigmaT[c] * std::exp(-sigmaT[c] * t);
    return w * s / 3;
}
double successMass(const Spectrum &sigmaT, double w, double a, double b) {
    double s = 0;
    for (int c = 0; c < 3; ++c) s += std::exp(-sigmaT[c] * a) - std::exp(-sigmaT[c] * b);
    return w * s / 3;
}

// Histogram of sampled interaction distances (plus a cell for "crossed the segment") against the
// densities, for a chromatic medium and for one with a channel that has no extinction at all.
TEST(HomogeneousMedium, DistanceSamplingMatchesDensities) {
    struct Case {
        Spectrum sigmaS, sigmaA;
        double w;  // expected default mediumSamplingWeight
    };
    const std::vector<Case> cases = {
        {{0.3, 0.6, 1.2}, {0.2, 0.1, 0.05}, 1.2 / 1.25},  // max albedo 0.96
        {{0.0, 0.5, 2.0}, {0.0, 0.0, 1.0}, 1.0},          // red channel empty, green albedo 1
        {{0.05, 0.05, 0.05}, {1.0, 1.0, 1.0}, 0.5},       // low albedo: w clamped up to 0.5
    };
    const double tmin = 0.25, length = 2.5;
    const int bins = 40, n = 200000;
    for (const Case &c : cases) {
        const auto medium = makeMedium(c.sigmaS, c.sigmaA);
        const Spectrum sigmaT = c.sigmaS + c.sigmaA;
        const Ray ray(Vec3(1, 2, 3), normalize(Vec3(1, 1, -1)), tmin, tmin + length);
        std::vector<double> observed(bins + 1, 0.0), expected(bins + 1, 0.0);
        PCG32 rng(7, 3);
        bool recordsOk = true;
        for (int i = 0; i < n; ++i) {
            MediumSample ms;
            if (medium->sampleDistance(ray, rng.nextDouble(), ms)) {
                const double d = ms.t - tmin;
                ASSERT_GE(d, 0.0);
                ASSERT_LT(d, length);
                observed[std::min(bins - 1, static_cast<int>(d / length * bins))] += 1;
                recordsOk &= std::abs(ms.pdfSuccess - successDensity(sigmaT, c.w, d)) < 1e-12 &&
                             ms.pdfSuccessRev == ms.pdfSuccess && (ms.p - ray(ms.t)).length() < 1e-12 &&
                             std::abs(ms.transmittance.g - std::exp(-sigmaT.g * d)) < 1e-12;
            } else {
                observed[bins] += 1;
                recordsOk &=
                    ms.t == ray.tmax && std::abs(ms.pdfFailure - (1 - successMass(sigmaT, c.w, 0, length))) < 1e-12;
            }
        }
        for (int b = 0; b < bins; ++b)
            expected[b] = n * successMass(sigmaT, c.w, length * b / bins, length * (b + 1) / bins);
        expected[bins] = n * (1 - successMass(sigmaT, c.w, 0, length));
        const Chi2Result r = chi2Histogram(observed, expected, 0.01, static_cast<int>(cases.size()));
        EXPECT_TRUE(r.passed) << "sigmaT " << sigmaT.r << "," << sigmaT.g << "," << sigmaT.b << ": " << r.report;
        EXPECT_TRUE(recordsOk) << "sampleDistance filled inconsistent densities or positions";
    }
}

// BDPT needs pdfSuccess and pdfFailure in both directions: the density of an interaction anywhere on
// the segment plus the probability of crossing it must be exactly one, for any segment length.
TEST(HomogeneousMedium, DistanceDensitiesIntegrateToOne) {
    const auto medium = makeMedium(Spectrum(0.4, 1.5, 3.0), Spectrum(0.1, 0.0, 1.0));
    for (double length : {0.01, 1.0, 7.5, 60.0}) {
        const double tmin = 0.5;
        const Vec3 o(0, 0, 0), d(0, 1, 0);
        const double mass = simpson(
            [&](double s) {
                MediumSample ms;
                medium->evalDistancePdf(Ray(o, d, tmin, tmin + s), true, ms);
                return ms.pdfSuccess;
            },
            0, length, 20000);
        MediumSample end;
        medium->evalDistancePdf(Ray(o, d, tmin, tmin + length), false, end);
        EXPECT_NEAR(mass + end.pdfFailure, 1.0, 1e-9) << "length " << length;
        EXPECT_EQ(end.pdfSuccessRev, end.pdfSuccess) << "a homogeneous density is the same from either end";
    }
}

// The weights the integrator applies, sigma_s T(t) / pdfSuccess on an interaction and T(L) / pdfFailure
// on a crossing, must estimate sigma_s * integral of T and T(L) in every channel, even though one
// distance serves all three channels (the point of the balance strategy).
TEST(HomogeneousMedium, ChromaticWeightsAreUnbiased) {
    const Spectrum sigmaS(0.2, 0.9, 2.5), sigmaA(0.3, 0.1, 0.5);
    const Spectrum sigmaT = sigmaS + sigmaA;
    const auto medium = makeMedium(sigmaS, sigmaA);
    const double length = 1.7;
    const Ray ray(Vec3(0, 0, 0), Vec3(0, 0, 1), 0, length);
    const int n = 400000;
    Spectrum sumIn, sumIn2, sumOut, sumOut2;
    PCG32 rng(11, 5);
    for (int i = 0; i < n; ++i) {
        MediumSample ms;
        Spectrum in, out;
        if (medium->sampleDistance(ray, rng.nextDouble(), ms))
            in = ms.sigmaS * ms.transmittance / ms.pdfSuccess;
        else
            out = ms.transmittance / ms.pdfFailure;
        sumIn += in;
        sumIn2 += in * in;
        sumOut += out;
        sumOut2 += out * out;
    }
    for (int c = 0; c < 3; ++c) {
        const double scattered = sigmaS[c] / sigmaT[c] * (1 - std::exp(-sigmaT[c] * length));
        const double crossed = std::exp(-sigmaT[c] * length);
        const double meanIn = sumIn[c] / n, meanOut = sumOut[c] / n;
        const double seIn = std::sqrt((sumIn2[c] / n - meanIn * meanIn) / n);
        const double seOut = std::sqrt((sumOut2[c] / n - meanOut * meanOut) / n);
        EXPECT_LT(seIn, 0.01 * scattered);
        EXPECT_NEAR(meanIn, scattered, 4 * seIn) << "channel " << c;
        EXPECT_NEAR(meanOut, crossed, 4 * seOut) << "channel " << c;
    }
}

TEST(HomogeneousMedium, TransmittanceIsBeerLambertAndSafeOnInfiniteSegments) {
    const auto medium = makeMedium(Spectrum(0.0, 0.5, 1.0), Spectrum(0.0, 0.25, 0.0));
    const Spectrum T = medium->evalTransmittance(Ray(Vec3(), Vec3(1, 0, 0), 1.0, 3.0));
    EXPECT_DOUBLE_EQ(T.r, 1.0);
    EXPECT_NEAR(T.g, std::exp(-0.75 * 2), 1e-15);
    EXPECT_NEAR(T.b, std::exp(-1.0 * 2), 1e-15);
    const Spectrum Tinf = medium->evalTransmittance(Ray(Vec3(), Vec3(1, 0, 0), 0.0, kInfinity));
    EXPECT_EQ(Tinf, Spectrum(1.0, 0.0, 0.0)) << "a channel without extinction transmits along an infinite ray";
    // mediumSamplingWeight is 1 here (blue albedo 1); u picks the channel in thirds. On an infinite
    // segment the red channel (no extinction) never interacts, the others always do.
    MediumSample ms;
    EXPECT_FALSE(medium->sampleDistance(Ray(Vec3(), Vec3(1, 0, 0)), 0.3, ms));
    EXPECT_EQ(ms.transmittance / ms.pdfFailure, Spectrum(3.0, 0.0, 0.0));
    EXPECT_TRUE(medium->sampleDistance(Ray(Vec3(), Vec3(1, 0, 0)), 0.5, ms));
    EXPECT_TRUE(std::isfinite(ms.t) && std::isfinite(ms.pdfSuccess) && ms.pdfSuccess > 0);
}

// Mitsuba 0.6's parameter conventions (src/medium/materials.h: lookupMaterial).
TEST(HomogeneousMedium, MitsubaParameterConventions) {
    Properties p = makeProps(ObjectKind::Medium, "homogeneous");
    setSpectrum(p, "sigmaT", Spectrum(2.0, 4.0, 1.0));
    setSpectrum(p, "albedo", Spectrum(0.25, 0.5, 1.0));
    setFloat(p, "scale", 3.0);
    auto m = makeMedium(p);
    EXPECT_EQ(m->sigmaT(), Spectrum(6.0, 12.0, 3.0));
    EXPECT_EQ(m->sigmaS(), Spectrum(1.5, 6.0, 3.0));
    EXPECT_EQ(m->phase().meanCosine(), 0.0) << "default phase function is isotropic";

    // Neither coefficients nor a preset: Mitsuba's default preset skin1, per millimetre times 100.
    m = makeMedium(makeProps(ObjectKind::Medium, "homogeneous"));
    EXPECT_NEAR(m->sigmaS().g, 88.0, 1e-9);
    EXPECT_NEAR(m->sigmaT().b, 101.0 + 48.0, 1e-9);
    // A coefficient left out comes from the preset.
    Properties partial = makeProps(ObjectKind::Medium, "homogeneous");
    setSpectrum(partial, "sigmaS", Spectrum(1.0));
    m = makeMedium(partial);
    EXPECT_NEAR(m->sigmaT().r, 1.0 + 3.2, 1e-9);
    Properties preset = makeProps(ObjectKind::Medium, "homogeneous");
    setString(preset, "material", "Ketchup");
    m = makeMedium(preset);
    EXPECT_NEAR(m->sigmaS().r, 18.0, 1e-9);
    // Presets with measured anisotropy, and a `g` parameter, give the reduced coefficient (1 - g) sigma_s
    // (Mitsuba 0.6's Medium constructor), not an HG phase function.
    Properties milk = makeProps(ObjectKind::Medium, "homogeneous");
    setString(milk, "material", "Regular Milk");
    m = makeMedium(milk);
    EXPECT_NEAR(m->sigmaS().r, 1820.52 * (1 - 0.75), 1e-9);
    EXPECT_EQ(m->phase().meanCosine(), 0.0);
    Properties reduced = makeProps(ObjectKind::Medium, "homogeneous");
    setSpectrum(reduced, "sigmaS", Spectrum(2.0));
    setSpectrum(reduced, "sigmaA", Spectrum(0.5));
    setFloat(reduced, "g", 0.25);
    m = makeMedium(reduced);
    EXPECT_EQ(m->sigmaS(), Spectrum(1.5));
    EXPECT_EQ(m->sigmaT(), Spectrum(2.0));

    // A nested phase function replaces the isotropic default.
    Properties nested = makeProps(ObjectKind::Medium, "homogeneous");
    setSpectrum(nested, "sigmaS", Spectrum(1.0));
    setSpectrum(nested, "sigmaA", Spectrum(0.0));
    nested.addChild({"", ObjectKind::Phase, makeHG(0.6), SourceLocation{"test.xml", 5}});
    m = makeMedium(nested);
    EXPECT_EQ(m->phase().meanCosine(), 0.6);
    nested.checkAllUsed();
}

// Each bad value must raise a SceneError that names the offending parameter.
TEST(HomogeneousMedium, BadParametersNameTheParameter) {
    const double nan = std::nan("");
    struct Bad {
        std::function<void(Properties &)> set;
        std::string param;
    };
    const std::vector<Bad> bad = {
        {[](Properties &p) { setSpectrum(p, "sigmaS", Spectrum(1, -0.5, 1)); }, "sigmaS"},
        {[](Properties &p) { setSpectrum(p, "sigmaA", Spectrum(-1)); }, "sigmaA"},
        {[&](Properties &p) { setSpectrum(p, "sigmaA", Spectrum(nan)); }, "sigmaA"},
        {[](Properties &p) { setSpectrum(p, "sigmaT", Spectrum(-2)); }, "sigmaT"},
        {[](Properties &p) { setSpectrum(p, "albedo", Spectrum(0.5, 1.5, 0.5)); }, "albedo"},
        {[&](Properties &p) { setSpectrum(p, "albedo", Spectrum(0.5, nan, 0.5)); }, "albedo"},
        {[](Properties &p) {
             setSpectrum(p, "sigmaS", Spectrum(1));
             setSpectrum(p, "sigmaT", Spectrum(1));
         },
         "sigmaT"},
        {[](Properties &p) { setFloat(p, "scale", -1); }, "scale"},
        {[](Properties &p) { setFloat(p, "g", 1.0); }, "g"},
        {[](Properties &p) { setSpectrum(p, "g", Spectrum(0.5, -1.2, 0.5)); }, "g"},
        {[&](Properties &p) { setFloat(p, "scale", nan); }, "scale"},
        {[](Properties &p) { setString(p, "material", "unobtainium"); }, "material"},
        {[](Properties &p) { setFloat(p, "mediumSamplingWeight", 1.5); }, "mediumSamplingWeight"},
        {[](Properties &p) { setFloat(p, "mediumSamplingWeight", 0.0); }, "mediumSamplingWeight"},
        {[](Properties &p) { setFloat(p, "densityMultiplier", 2.0); }, "densityMultiplier"},
        {[](Properties &p) { setString(p, "strategy", "maximum"); }, "strategy"},
    };
    for (const Bad &b : bad) {
        Properties p = makeProps(ObjectKind::Medium, "homogeneous");
        b.set(p);
        try {
            makeMedium(p);
            ADD_FAILURE() << "no error for a bad '" << b.param << "'";
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("'" + b.param + "'"), std::string::npos) << e.what();
        }
    }
    for (double g : {1.0, -1.0, 1.5, nan}) {
        Properties p = makeProps(ObjectKind::Phase, "hg");
        setFloat(p, "g", g);
        try {
            build(phasePlugins(), "hg", p);
            ADD_FAILURE() << "no error for g = " << g;
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("'g'"), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace pf::test
