// Bidirectional path tracing: agreement with the path tracer on every shared scene, closed-form scenes,
// the per-strategy images, determinism, regeneration of recorded paths, and parameter checking.
//
// Comparisons are per-block means of images rendered with independent seeds: each seed's image is an
// independent estimate, so the seed-to-seed spread of a block mean gives its standard error, whatever
// the correlations between pixels (light tracing splats one light path into several pixels).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "integrators/bdpt.h"
#include "path/mutation.h"
#include "support/agreement.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

namespace fs = std::filesystem;

// 32 seeds and 8x8 blocks: the ~400 comparisons of this file (support/agreement.h).
constexpr int kSeeds = 32, kBlock = 8;

void expectAgreement(const Scene &scene, const Integrator &reference, int referenceSpp, const Integrator &bdpt,
                     int bdptSpp, const std::string &what) {
    expectAgreement(blockStats(scene, reference, kBlock, kSeeds, referenceSpp),
                    blockStats(scene, bdpt, kBlock, kSeeds, bdptSpp), what);
}

std::unique_ptr<Integrator> fileIntegrator(const Scene &scene, const std::string &type) {
    return createIntegrator(type, scene.integratorProperties(), false);
}

// Every shared scene, with the scene's own maxDepth and strictNormals. Two need a larger light for the
// path tracer to converge in test time, which leaves their light transport the same: the ring's 0.2 x 0.2
// light is seen through the gold mirror only by paths that hit it by chance (x15 in size, same radiance),
// and the volumetric caustic's 5 x 4 mm light only through the glass sphere (x40, radiance / 1600).
struct SharedScene {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const SharedScene &c, std::ostream *os) { *os << c.name; }
    std::string name;
    std::vector<Edit> edits;
    int resolution, referenceSpp, bdptSpp;
};

class SharedScenes : public ::testing::TestWithParam<SharedScene> {};

TEST_P(SharedScenes, AgreeWithThePathTracer) {
    const SharedScene &p = GetParam();
    auto scene = loadSharedScene(p.name, p.resolution, p.edits);
    // volumetric-caustic names volpath; the others path.
    const std::string reference = scene->integratorProperties().pluginName();
    expectAgreement(*scene, *fileIntegrator(*scene, reference), p.referenceSpp, *fileIntegrator(*scene, "bdpt"),
                    p.bdptSpp, p.name);
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, SharedScenes,
    ::testing::Values(SharedScene{"cornell-box", {}, 32, 8, 2}, SharedScene{"veach-mis", {}, 32, 8, 2},
                      SharedScene{"veach-bidir", {}, 24, 64, 4},
                      SharedScene{"ring-caustic",
                                  {{R"(<scale x="0.1" y="0.1" z="0.1"/>)", R"(<scale x="1.5" y="1.5" z="1.5"/>)"}},
                                  32,
                                  64,
                                  8},
                      SharedScene{"volumetric-caustic",
                                  {{"-0.0025 -1.91069e-015", "-0.1 -1.91069e-015"},
                                   {"0 -0.002 -8.74228e-011", "0 -0.08 -8.74228e-011"},
                                   {"541127, 381972, 127324", "338.2, 238.7, 79.58"}},
                                  24,
                                  64,
                                  4}),
    [](const ::testing::TestParamInfo<SharedScene> &info) {
        std::string name = info.param.name;
        for (char &c : name)
            if (c == '-') c = '_';
        return name;
    });

// A thin lens (so that the emitter walk can hit the lens: t = 0), an environment or parallel light, an
// index-matched box of fog, glass, glossy and mixed surfaces, an area light and a point light behind the
// camera (through a lens a visible point light would be a blurred disk that the path tracer cannot see).
std::string lensScene(const std::string &sky, int maxDepth, int res, double aperture = 0.15) {
    const std::string skyEmitter =
        sky == "directional" ? R"(<emitter type="directional"><vector name="direction" x="-0.3" y="-1" z="-0.2"/>
                 <spectrum name="irradiance" value="0.5"/></emitter>)"
                             : R"(<emitter type="constant"><spectrum name="radiance" value="0.2"/></emitter>)";
    return R"(<scene version="0.6.0">
        <integrator type="volpath"><integer name="maxDepth" value=")" +
           std::to_string(maxDepth) + R"("/>
            <boolean name="strictNormals" value="true"/></integrator>
        <sensor type="thinlens"><float name="apertureRadius" value=")" +
           std::to_string(aperture) + R"("/>
            <float name="focusDistance" value="4"/><float name="fov" value="50"/>
            <transform name="toWorld"><lookat origin="0, 1, 5" target="0, 0.8, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value=")" +
           std::to_string(res) + R"("/>
                <integer name="height" value=")" +
           std::to_string(res) + R"("/><rfilter type="box"/></film></sensor>
        <medium type="homogeneous" id="fog"><rgb name="sigmaS" value="0.6, 0.8, 1.0"/><rgb name="sigmaA" value="0.1"/>
            <phase type="hg"><float name="g" value="0.4"/></phase></medium>
        <shape type="rectangle"><transform name="toWorld"><scale value="3"/><rotate x="1" angle="-90"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
        <shape type="rectangle"><transform name="toWorld"><scale value="3"/><translate z="-2"/></transform>
            <bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="cube"><transform name="toWorld"><scale value="0.5"/><translate x="1" y="0.5"/></transform>
            <ref name="interior" id="fog"/></shape>
        <shape type="sphere"><point name="center" x="-1" y="0.6" z="0"/><float name="radius" value="0.5"/>
            <bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="sphere"><point name="center" x="0" y="0.4" z="1"/><float name="radius" value="0.4"/>
            <bsdf type="plastic"/></shape>
        <shape type="rectangle"><transform name="toWorld"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="3"/>
            </transform><emitter type="area"><spectrum name="radiance" value="6"/></emitter></shape>
        <emitter type="point"><point name="position" x="1" y="2" z="5.5"/><spectrum name="intensity" value="3"/></emitter>
        )" +
           skyEmitter + "</scene>";
}

TEST(BDPT, AgreesWithVolpathThroughALens) {
    for (const std::string sky : {"constant", "directional"}) {
        auto scene = loadScene(writeFile(tempDir("bdpt-lens-" + sky), "scene.xml", lensScene(sky, 6, 32)));
        expectAgreement(*scene, *fileIntegrator(*scene, "volpath"), 16, *fileIntegrator(*scene, "bdpt"), 2, sky);
    }
}

// Every variant of the estimator is unbiased on a scene without Dirac paths that only light tracing finds:
// the balance heuristic, no direct sampling, no light image.
TEST(BDPT, VariantsAgree) {
    auto scene = loadSharedScene("cornell-box", 32);
    const Properties &fileProps = scene->integratorProperties();
    const auto variant = [&](const std::string &name, Properties::Type type, const Properties::Value &value) {
        Properties props(ObjectKind::Integrator, "bdpt", {});
        props.set("maxDepth", Properties::Type::Integer, fileProps.getInt("maxDepth"), {});
        props.set(name, type, value, {});
        return createIntegrator("bdpt", props, true);
    };
    const BlockStats path = blockStats(*scene, *fileIntegrator(*scene, "path"), kBlock, kSeeds, 8);
    const auto check = [&](const std::unique_ptr<Integrator> &bdpt, const std::string &what) {
        expectAgreement(path, blockStats(*scene, *bdpt, kBlock, kSeeds, 2), what);
    };
    check(variant("heuristic", Properties::Type::String, std::string("balance")), "balance heuristic");
    check(variant("sampleDirect", Properties::Type::Boolean, false), "no direct sampling");
    check(variant("lightImage", Properties::Type::Boolean, false), "no light image");
}

// Camera at the centre of a sphere that emits Le inwards and reflects diffusely with albedo rho: every
// pixel sees Le (1 + rho + ... + rho^(maxDepth - 1)). maxDepth counts edges as in the path tracer.
TEST(BDPT, MaxDepthCountsEdgesLikeThePathTracer) {
    const double Le = 1.0, rho = 0.5;
    double expected = 0, term = Le;
    for (int depth = 1; depth <= 4; ++depth) {
        expected += term;
        term *= rho;
        const std::string xml = R"(<scene version="0.6.0"><integrator type="bdpt"><integer name="maxDepth" value=")" +
                                std::to_string(depth) + R"("/></integrator>
            <sensor type="perspective"><transform name="toWorld"><lookat origin="0, 0, 0" target="0, 0, 1"/></transform>
                <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
            <shape type="sphere"><float name="radius" value="10"/><boolean name="flipNormals" value="true"/>
                <bsdf type="diffuse"><spectrum name="reflectance" value=")" +
                                std::to_string(rho) +
                                R"("/></bsdf><emitter type="area"><spectrum name="radiance" value=")" +
                                std::to_string(Le) + R"("/></emitter></shape></scene>)";
        const RenderOutput out = renderXml(xml, "bdpt", 16, 3);
        const MeanCI m = regionMean(out.image, 0, 0, out.image.width, out.image.height);
        EXPECT_LT(m.stderr_, 0.005 * expected) << "maxDepth " << depth << ": too noisy";
        EXPECT_NEAR(m.mean, expected, 4 * m.stderr_ + 1e-9) << "maxDepth " << depth;
    }
}

// The per-strategy images (s + t <= maxDepth + 1) add up to the image, and the strategyImages parameter
// writes them.
TEST(BDPT, StrategyImagesSumToTheImage) {
    const std::string dir = tempDir("bdpt-strategies");
    auto scene = loadScene(writeFile(dir, "scene.xml", lensScene("constant", 4, 16, 0.5)));
    Properties props(ObjectKind::Integrator, "bdpt", {});
    props.set("maxDepth", Properties::Type::Integer, int64_t(4), {});
    props.set("strategyImages", Properties::Type::String, dir + "/strategies", {});
    const BDPT bdpt(props);
    RenderOptions opt;
    // The emitter walk reaches the lens (t = 0) about once per 900 walks here (19 pixels at 64 spp): at 4 spp
    // (1,024 walks) a render without such a hit had a chance of about 0.3, at 64 spp of about e^-18.
    opt.spp = 64;
    opt.seed = 5;
    opt.threads = 2;
    RenderStats stats;
    const Bitmap image = bdpt.render(*scene, opt, stats);
    const std::vector<StrategyImage> strategies = bdpt.renderStrategyImages(*scene, opt);
    ASSERT_EQ(strategies.size(), 3u + 4u + 5u + 6u);  // n = 2 .. 5 vertices, n + 1 strategies each
    std::vector<double> sum(image.rgb.size(), 0.0);
    double lens = 0, hits = 0;
    for (const StrategyImage &si : strategies) {
        const auto [s, t] = si.strategy;
        EXPECT_TRUE(fs::exists(dir + "/strategies/s" + std::to_string(s) + "_t" + std::to_string(t) + ".exr"));
        for (size_t i = 0; i < sum.size(); ++i) {
            sum[i] += si.image.rgb[i];
            if (t == 0) lens += si.image.rgb[i];
            if (s == 0) hits += si.image.rgb[i];
        }
    }
    EXPECT_GT(lens, 0.0) << "the emitter walk never hit the lens";
    EXPECT_GT(hits, 0.0);
    for (size_t i = 0; i < sum.size(); ++i) EXPECT_NEAR(sum[i], image.rgb[i], 1e-5 * std::max(1.0, std::abs(sum[i])));
}

// Same seed, same bits with one and two threads, light-traced splats included.
TEST(BDPT, SameBitsWithOneAndTwoThreads) {
    const std::string xml = lensScene("constant", 5, 24);
    const RenderOutput a = renderXml(xml, "bdpt", 4, 7, 1), b = renderXml(xml, "bdpt", 4, 7, 2);
    ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
    EXPECT_EQ(0, std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)));
    const RenderOutput c = renderXml(xml, "bdpt", 4, 8, 2);
    EXPECT_NE(0, std::memcmp(a.image.rgb.data(), c.image.rgb.data(), a.image.rgb.size() * sizeof(float)))
        << "a different seed must give a different image";
}

// A path recorded as (pixel, sample index, s, t) regenerates exactly from the seed: the same weighted
// contribution bits, and the same path.
TEST(BDPT, RegeneratesRecordedPaths) {
    auto scene = loadScene(writeFile(tempDir("bdpt-records"), "scene.xml", lensScene("constant", 5, 8)));
    Properties props(ObjectKind::Integrator, "bdpt", {});
    const BDPT bdpt(props);
    constexpr uint64_t kSeed = 99;
    const Film &film = scene->sensor().film();
    int records = 0;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
            for (uint64_t index = 0; index < 2; ++index) {
                // The sample as the render loop draws it (render/image_task.cpp).
                const uint64_t pixel = static_cast<uint64_t>(y) * film.width() + x;
                IndependentSampler sampler(kSeed, pixel, index);
                const Vec2 raster = Vec2(x, y) + sampler.next2D();
                bdpt.evaluate(*scene, sampler, raster, [&](const StrategySample &original) {
                    const MutablePath path(*original.path);
                    const Spectrum f = contribution(*scene, path);
                    const PathRecord record{pixel, index, original.s, original.t};
                    int found = 0;
                    EXPECT_TRUE(bdpt.regenerate(*scene, kSeed, record, [&](const StrategySample &again) {
                        ++found;
                        EXPECT_EQ(again.value, original.value);
                        EXPECT_EQ(again.raster.x, original.raster.x);
                        EXPECT_EQ(again.raster.y, original.raster.y);
                        const MutablePath regenerated(*again.path);
                        ASSERT_EQ(regenerated.length(), path.length());
                        for (int i = 0; i < path.length(); ++i)
                            EXPECT_EQ(regenerated.vertex(i).position(), path.vertex(i).position());
                        EXPECT_EQ(contribution(*scene, regenerated), f);
                    }));
                    EXPECT_EQ(found, 1);
                    ++records;
                });
            }
    EXPECT_GT(records, 200);
}

TEST(BDPT, RejectsBadParameters) {
    const auto make = [](const std::string &name, Properties::Type type, const Properties::Value &value) {
        Properties props(ObjectKind::Integrator, "bdpt", {});
        props.set(name, type, value, {});
        return createIntegrator("bdpt", props, true);
    };
    EXPECT_THROW(make("maxDepth", Properties::Type::Integer, int64_t(0)), SceneError);
    EXPECT_THROW(make("maxDepth", Properties::Type::Integer, int64_t(-2)), SceneError);
    EXPECT_THROW(make("rrDepth", Properties::Type::Integer, int64_t(0)), SceneError);
    EXPECT_THROW(make("heuristic", Properties::Type::String, std::string("cutoff")), SceneError);
    EXPECT_THROW(make("strategyImages", Properties::Type::String, std::string("out")), SceneError)
        << "per-strategy images need a finite maxDepth";
    EXPECT_THROW(make("maxDepht", Properties::Type::Integer, int64_t(3)), SceneError) << "misspelt parameter";
    EXPECT_THROW(make("strictNormals", Properties::Type::Boolean, true), SceneError) << "not a bdpt parameter";
    EXPECT_THROW(make("lightImage", Properties::Type::Integer, int64_t(1)), SceneError) << "wrong type";
    EXPECT_NO_THROW(make("sampleDirect", Properties::Type::Boolean, false));
}

}  // namespace
}  // namespace pf::test
