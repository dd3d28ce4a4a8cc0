// The volumetric path tracer against closed forms: Beer-Lambert attenuation through index-matched
// medium boundaries, single scattering in a spherical shell (closed form up to a deterministic
// quadrature computed here), the medium furnace (a conservative medium inside a uniform emitter leaves
// the radiance unchanged), agreement with `path` on a scene without media, and the volumetric-caustic
// scene. Comparisons are confidence intervals (4 standard errors) at fixed seeds, and each checks that
// its standard error is small enough for the comparison to mean something.
//
// The shell scenes put the camera at the centre of two concentric index-matched spheres of radii R1 < R2
// with the medium between them, inside a black sphere of radius 10 that emits Le inwards. Every camera
// ray is radial, so every pixel has the same expected value.
//
// Depths count the index-matched crossings as Mitsuba 0.6 does (README "Path depth"): a camera ray
// crosses R1 (depth 1) and R2 (2) before it reaches the emitter (3), so unscattered light needs maxDepth
// 3; light scattered once in the shell towards the emitter without meeting the inner ball needs 4, and
// once towards the inner ball, which it crosses twice, 6.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "support/render_util.h"
#include "support/seed_stats.h"

namespace pf::test {
namespace {

constexpr double kR1 = 1.0, kR2 = 2.0, kLe = 1.0;

struct MediumSpec {
    Spectrum sigmaS, sigmaA;
    double g = 0;  // 0 = no nested phase function (Mitsuba's isotropic default)
};

std::string rgb(const Spectrum &s) {
    return std::to_string(s.r) + ", " + std::to_string(s.g) + ", " + std::to_string(s.b);
}

// outerBSDF: an optional BSDF element for the outer boundary (default: none, i.e. index-matched).
std::string shellScene(const MediumSpec &m, int maxDepth, double wallReflectance = 0, bool hideEmitters = false,
                       const std::string &outerBSDF = "") {
    const std::string phase =
        m.g != 0 ? R"(<phase type="hg"><float name="g" value=")" + std::to_string(m.g) + R"("/></phase>)" : "";
    return R"(<scene version="0.6.0"><integrator type="volpath"><integer name="maxDepth" value=")" +
           std::to_string(maxDepth) + R"("/><boolean name="hideEmitters" value=")" + (hideEmitters ? "true" : "false") +
           R"("/></integrator>
        <sensor type="perspective"><float name="fov" value="50"/>
          <transform name="toWorld"><lookat origin="0, 0, 0" target="0.2, 0.1, 1" up="0, 1, 0"/></transform>
          <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
            <rfilter type="box"/></film></sensor>
        <medium type="homogeneous" id="m"><rgb name="sigmaS" value=")" +
           rgb(m.sigmaS) + R"("/><rgb name="sigmaA" value=")" + rgb(m.sigmaA) + R"("/>)" + phase + R"(</medium>
        <shape type="sphere"><float name="radius" value=")" +
           std::to_string(kR1) + R"("/><ref name="exterior" id="m"/></shape>
        <shape type="sphere"><float name="radius" value=")" +
           std::to_string(kR2) + R"("/><ref name="interior" id="m"/>)" + outerBSDF + R"(</shape>
        <shape type="sphere"><float name="radius" value="10"/><boolean name="flipNormals" value="true"/>
          <bsdf type="diffuse"><rgb name="reflectance" value=")" +
           std::to_string(wallReflectance) + R"("/></bsdf><emitter type="area"><rgb name="radiance" value=")" +
           std::to_string(kLe) + R"("/></emitter></shape></scene>)";
}

void expectChannelMeans(const Bitmap &img, const Spectrum &expected, double maxRelStderr, const std::string &what) {
    for (int c = 0; c < 3; ++c) {
        const MeanCI m = regionMean(img, 0, 0, img.width, img.height, c);
        EXPECT_LT(m.stderr_, maxRelStderr * expected[c]) << what << ", channel " << c << ": too noisy to compare";
        EXPECT_NEAR(m.mean, expected[c], 4 * m.stderr_ + 1e-9 * expected[c])
            << what << ", channel " << c << " (stderr " << m.stderr_ << ")";
    }
}

// A purely absorbing medium between index-matched boundaries: the default mediumSamplingWeight is 0
// there, so the attenuation is deterministic and exact, Le exp(-sigma_t (R2 - R1)), in every pixel.
TEST(VolPath, BeerLambertThroughIndexMatchedBoundaries) {
    const MediumSpec m{Spectrum(0.0), Spectrum(0.3, 0.9, 2.0)};
    const RenderOutput out = renderXml(shellScene(m, -1), "volpath", 4, 1, 2);
    const Spectrum expected = kLe * exp(m.sigmaA * -(kR2 - kR1));
    for (int c = 0; c < 3; ++c) {
        const MeanCI mean = regionMean(out.image, 0, 0, out.image.width, out.image.height, c);
        EXPECT_NEAR(mean.mean, expected[c], 1e-6 * expected[c]) << "channel " << c;
        EXPECT_LT(mean.stderr_, 1e-6 * expected[c]) << "channel " << c;
    }
}

// A scattering, chromatic medium with maxDepth = 1: medium interactions are scattering events, so only
// the light that crosses unscattered is counted, Le exp(-sigma_t (R2 - R1)), now estimated through
// free-flight sampling (crossing weight T / pdfFailure).
// The camera itself inside a medium (an unnamed medium child of <sensor>): an absorbing medium filling
// everything inside the emitting sphere attenuates its radiance by exp(-sigma_a * 10).
TEST(VolPath, CameraInsideAMedium) {
    const Spectrum sigmaA(0.05, 0.1, 0.2);
    const std::string xml = R"(<scene version="0.6.0"><integrator type="volpath"/>
        <medium type="homogeneous" id="fog"><rgb name="sigmaS" value="0, 0, 0"/><rgb name="sigmaA" value=")" +
                            rgb(sigmaA) + R"("/></medium>
        <sensor type="perspective"><float name="fov" value="50"/><ref id="fog"/>
          <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
            <rfilter type="box"/></film></sensor>
        <shape type="sphere"><float name="radius" value="10"/><boolean name="flipNormals" value="true"/>
          <ref name="interior" id="fog"/><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
          <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>)";
    const RenderOutput out = renderXml(xml, "volpath", 2, 1, 2);
    for (int c = 0; c < 3; ++c) {
        const MeanCI m = regionMean(out.image, 0, 0, out.image.width, out.image.height, c);
        EXPECT_NEAR(m.mean, std::exp(-sigmaA[c] * 10), 1e-6) << "channel " << c;
    }
}

TEST(VolPath, MaxDepthThreeSeesOnlyUnscatteredLight) {
    const MediumSpec m{Spectrum(0.5, 0.2, 1.5), Spectrum(0.1, 0.4, 0.2)};
    const RenderOutput out = renderXml(shellScene(m, 3), "volpath", 32, 2, 2);
    expectChannelMeans(out.image, kLe * exp((m.sigmaS + m.sigmaA) * -(kR2 - kR1)), 0.01, "maxDepth 3");
    // With fewer, the emitter lies beyond the two crossings.
    for (int depth : {1, 2}) {
        const RenderOutput none = renderXml(shellScene(m, depth), "volpath", 4, 2, 2);
        EXPECT_EQ(regionMean(none.image, 0, 0, none.image.width, none.image.height).mean, 0.0) << "maxDepth " << depth;
    }
}

// Path length inside the shell from radius r in a direction whose cosine with the outward radial
// direction is mu: up to the outer sphere, minus the chord through the inner (vacuum) ball.
double shellChord(double r, double mu) {
    const double s2 = r * r * (1 - mu * mu);
    double length = -r * mu + std::sqrt(kR2 * kR2 - s2);
    if (mu < 0 && s2 < kR1 * kR1) length -= 2 * std::sqrt(kR1 * kR1 - s2);
    return length;
}

double simpson(const std::function<double(double)> &f, double a, double b, int n) {
    const double h = (b - a) / n;
    double sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
    return sum * h / 3.0;
}

// Radiance along a radial camera ray with at most one scattering event:
//   Le [ exp(-st (R2-R1)) + ss Int_{R1}^{R2} exp(-st (r-R1)) Int_{-1}^{1} 2 pi p(mu) exp(-st chord(r,mu)) dmu dr ],
// p the HG density of the angle between the camera ray (outwards) and the direction towards the light.
// The mu integrand has a kink where the direction grazes the inner ball; the quadrature splits there.
// The directions below the kink cross the inner ball (two crossings more): at maxDepth 4 only the
// directions above it count (`missInnerBall`).
Spectrum singleScatteringReference(const MediumSpec &m, bool missInnerBall = true) {
    Spectrum result;
    for (int c = 0; c < 3; ++c) {
        const double st = m.sigmaS[c] + m.sigmaA[c], ss = m.sigmaS[c], g = m.g;
        auto phase = [&](double mu) {
            const double d = 1 + g * g - 2 * g * mu;
            return (1 - g * g) / (4 * kPi * d * std::sqrt(d));
        };
        auto inner = [&](double r) {
            auto f = [&](double mu) { return 2 * kPi * phase(mu) * std::exp(-st * shellChord(r, mu)); };
            const double kink = -std::sqrt(std::max(0.0, 1 - kR1 * kR1 / (r * r)));
            return (missInnerBall ? 0.0 : simpson(f, -1, kink, 2000)) + simpson(f, kink, 1, 2000);
        };
        const double scattered = simpson([&](double r) { return std::exp(-st * (r - kR1)) * inner(r); }, kR1, kR2, 400);
        result[c] = kLe * (std::exp(-st * (kR2 - kR1)) + ss * scattered);
    }
    return result;
}

// Single scattering (maxDepth = 4: two crossings, the scattering event, the crossing out of the shell)
// exercises next-event estimation from medium vertices, phase sampling with the MIS walk through
// index-matched boundaries within the remaining depth, and medium tracking across them.
TEST(VolPath, SingleScatteringMatchesQuadrature) {
    const MediumSpec iso{Spectrum(0.4, 0.8, 1.2), Spectrum(0.1, 0.1, 0.3)};
    expectChannelMeans(renderXml(shellScene(iso, 4), "volpath", 32, 3, 2).image, singleScatteringReference(iso), 0.01,
                       "isotropic");
    const MediumSpec forward{Spectrum(0.9, 0.5, 1.4), Spectrum(0.2, 0.3, 0.1), 0.6};
    expectChannelMeans(renderXml(shellScene(forward, 4), "volpath", 32, 4, 2).image, singleScatteringReference(forward),
                       0.01, "hg g = 0.6");
}

// hideEmitters (Mitsuba): an emitter seen directly, here through the medium, disappears, but the light
// it casts does not. With maxDepth = 4 exactly the single-scattered part of the reference remains.
TEST(VolPath, HideEmittersKeepsScatteredLight) {
    const MediumSpec m{Spectrum(0.4, 0.8, 1.2), Spectrum(0.1, 0.1, 0.3)};
    const Spectrum direct = kLe * exp((m.sigmaS + m.sigmaA) * -(kR2 - kR1));
    expectChannelMeans(renderXml(shellScene(m, 4, 0, true), "volpath", 32, 6, 2).image,
                       singleScatteringReference(m) - direct, 0.015, "hideEmitters");
}

// Medium furnace: the emitting sphere also reflects diffusely (albedo rho), so without absorption in the
// medium the uniform radiance Le / (1 - rho) solves the radiative transfer equation (in-scattering
// replaces exactly what extinction removes, and the wall returns Le + rho L). All orders of scattering,
// at surfaces and in the medium, with both MIS strategies and Russian roulette, must give it. The second
// case makes the outer medium boundary a lossless thin dielectric, whose transmission is a Null lobe
// that shadow rays and emitter walks cross while the path samples it: counting that light twice, or
// not at all, breaks the furnace.
TEST(VolPath, ConservativeMediumFurnace) {
    const MediumSpec m{Spectrum(0.8, 1.0, 1.25), Spectrum(0.0), -0.4};
    const double rho = 0.5;
    expectChannelMeans(renderXml(shellScene(m, -1, rho), "volpath", 64, 5, 2).image, Spectrum(kLe / (1 - rho)), 0.01,
                       "furnace");
    expectChannelMeans(
        renderXml(shellScene(m, -1, rho, false, R"(<bsdf type="thindielectric"/>)"), "volpath", 64, 7, 2).image,
        Spectrum(kLe / (1 - rho)), 0.01, "furnace with a thin dielectric boundary");
}

// Per-block luminance means of a scene file rendered with independent seeds, with their standard errors
// taken from the seed-to-seed spread (each seed's image is an independent estimate).
struct BlockStats {
    std::vector<double> mean, stderr_;
};

BlockStats blockStats(const std::string &scenePath, const std::string &integrator, int width, int height, int block,
                      uint64_t firstSeed, int seeds, int spp) {
    auto scene = loadScene(scenePath);
    scene->resizeFilm(width, height);
    // Directly visible emitters only add the noise of their sub-pixel coverage; what is compared here is
    // the light they cast.
    Properties props = scene->integratorProperties();
    props.set("hideEmitters", Properties::Type::Boolean, true, props.location());
    const auto integ = createIntegrator(integrator, props, false);
    const int nx = width / block, ny = height / block;
    std::vector<double> sum(nx * ny, 0.0), sum2(sum.size(), 0.0);
    for (int s = 0; s < seeds; ++s) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = firstSeed + static_cast<uint64_t>(s);
        opt.threads = 2;
        RenderStats stats;
        const Bitmap img = integ->render(*scene, opt, stats);
        for (int by = 0; by < ny; ++by)
            for (int bx = 0; bx < nx; ++bx) {
                const double v = regionMean(img, bx * block, by * block, (bx + 1) * block, (by + 1) * block).mean;
                sum[by * nx + bx] += v;
                sum2[by * nx + bx] += v * v;
            }
    }
    BlockStats r;
    seedMeanAndError(sum, sum2, seeds, r.mean, r.stderr_);
    return r;
}

// Without media, volpath must estimate the same image as path (the scene file's maxDepth and
// strictNormals apply to both, emitters are hidden). The Cornell box checks indirect light; Veach's MIS scene, where
// glossy plates reflect lights of very different sizes, checks that the two MIS weights are those of path. Each
// compares 9 or 12 blocks of two 24-seed means; 5 combined standard errors keep the family-wise
// false-alarm rate well under 1% (Student t, 23 dof).
TEST(VolPath, AgreesWithPathWithoutMedia) {
    struct Case {
        const char *scene;
        int width, height, block, spp;
    };
    for (const Case &c : {Case{"cornell-box", 24, 24, 8, 4}, Case{"veach-mis", 32, 24, 8, 8}}) {
        const std::string path = std::string(PATHFARM_SOURCE_DIR) + "/scenes/" + c.scene + "/scene.xml";
        // Disjoint seeds: path and volpath draw their random numbers in the same order, so equal seeds would
        // give nearly equal images and the test would not be the two-sample comparison it claims to be.
        const BlockStats a = blockStats(path, "path", c.width, c.height, c.block, 1000, 24, c.spp);
        const BlockStats b = blockStats(path, "volpath", c.width, c.height, c.block, 2000, 24, c.spp);
        size_t precise = 0;
        for (size_t i = 0; i < a.mean.size(); ++i) {
            const double se = std::sqrt(a.stderr_[i] * a.stderr_[i] + b.stderr_[i] * b.stderr_[i]);
            if (se < 0.05 * a.mean[i]) ++precise;
            EXPECT_NEAR(a.mean[i], b.mean[i], 5 * se) << c.scene << ", block " << i;
        }
        // Blocks that show a light's highlight on a near-specular plate stay noisy (sub-pixel coverage of a
        // tiny bright reflection); the comparison is meaningful as long as most blocks are precise.
        EXPECT_GE(4 * precise, 3 * a.mean.size()) << c.scene << ": too noisy to compare";
    }
}

// The volumetric-caustic scene (media on a null front wall, a dielectric sphere and the light, strict
// normals) renders at low resolution with every sample finite and non-negative. The render loop would
// drop non-finite samples silently, so the samples are drawn here one by one.
TEST(VolPath, VolumetricCausticSamplesAreFinite) {
    auto scene = loadScene(std::string(PATHFARM_SOURCE_DIR) + "/scenes/volumetric-caustic/scene.xml");
    const int res = 16;
    scene->resizeFilm(res, res);
    const Properties &fileProps = scene->integratorProperties();
    ASSERT_EQ(fileProps.pluginName(), "volpath");
    const auto integ = createIntegrator("volpath", fileProps, true);
    const auto *sampling = dynamic_cast<const SamplingIntegrator *>(integ.get());
    ASSERT_NE(sampling, nullptr);
    IndependentSampler sampler;
    SplatList splats;
    int bad = 0, lit = 0;
    double sum = 0;
    for (int y = 0; y < res; ++y)
        for (int x = 0; x < res; ++x)
            for (int s = 0; s < 8; ++s) {
                sampler.start(9, static_cast<uint64_t>(y * res + x), static_cast<uint64_t>(s));
                const Spectrum L = sampling->sample(*scene, sampler, Vec2(x, y) + sampler.next2D(), splats);
                if (!L.isValid()) ++bad;
                if (L.max() > 0) ++lit;
                sum += L.isValid() ? L.luminance() : 0.0;
            }
    EXPECT_EQ(bad, 0) << "non-finite or negative samples";
    EXPECT_GT(lit, res * res * 8 / 2) << "most camera paths should see in-scattered light";
    EXPECT_GT(sum, 0.0);
}

}  // namespace
}  // namespace pf::test
