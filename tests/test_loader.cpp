// Feature tests of the Mitsuba 0.5/0.6 XML loader: parameters and $substitution, includes, references,
// transform composition, colour and spectrum conversion, Properties semantics, and the shipped scenes.
// Values that no plugin interprets are read back through the integrator's Properties, which the loader
// hands to the scene unchecked.
#include <gtest/gtest.h>

#include <filesystem>

#include "bsdf/bsdf.h"
#include "scene/medium.h"
#include "scene/plugins.h"
#include "scene/sampler_settings.h"
#include "scene/scene.h"
#include "scene/spectrum_convert.h"
#include "support/render_util.h"
#include "texture/texture.h"

namespace pf {
namespace {

namespace fs = std::filesystem;

// Every scene needs a sensor and something to render.
const char *kSensorAndLight = R"(
  <emitter type="constant"/>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
  </sensor>
)";

std::string sceneXml(const std::string &body, const std::string &version = "0.6.0") {
    return "<scene version=\"" + version + "\">\n" + kSensorAndLight + body + "\n</scene>\n";
}

// Writes a scene into a fresh directory named after the running test and loads it.
std::unique_ptr<Scene> load(const std::string &body,
                            const std::vector<std::pair<std::string, std::string>> &defines = {},
                            const std::string &version = "0.6.0") {
    const std::string dir = test::tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
    return loadScene(test::writeFile(dir, "scene.xml", sceneXml(body, version)), defines);
}

// Message of the SceneError that loading `body` throws ("" if it loads).
std::string loadError(const std::string &body) {
    try {
        load(body);
    } catch (const SceneError &e) {
        return e.what();
    }
    return "";
}

void expectSpectrumNear(const Spectrum &s, const Spectrum &expected, double tol) {
    EXPECT_NEAR(s.r, expected.r, tol);
    EXPECT_NEAR(s.g, expected.g, tol);
    EXPECT_NEAR(s.b, expected.b, tol);
}

void expectMatrixNear(const Matrix4 &m, const std::array<std::array<double, 4>, 4> &expected) {
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_NEAR(m.m[i][j], expected[i][j], 1e-12) << "entry " << i << "," << j;
}

TEST(Loader, DefaultsSubstituteAndCommandLineDefinesOverrideThem) {
    const std::string body = R"(
  <default name="depth" value="7"/>
  <default name="depthMax" value="9"/>
  <integrator type="path">
    <integer name="maxDepth" value="$depth"/>
    <string name="label" value="$depth-$depthMax/$depth"/>
  </integrator>)";
    auto a = load(body);
    EXPECT_EQ(a->integratorProperties().getInt("maxDepth"), 7);
    // The longest defined name wins at each '$', so $depthMax is not read as $depth + "Max".
    EXPECT_EQ(a->integratorProperties().getString("label"), "7-9/7");
    auto b = load(body, {{"depth", "3"}});
    EXPECT_EQ(b->integratorProperties().getInt("maxDepth"), 3);
    EXPECT_EQ(b->integratorProperties().getString("label"), "3-9/3");
}

TEST(Loader, UndefinedParameterNamesIt) {
    const std::string msg =
        loadError(R"(<integrator type="path"><integer name="maxDepth" value="$depth"/></integrator>)");
    EXPECT_NE(msg.find("undefined parameter '$depth'"), std::string::npos) << msg;
}

TEST(Loader, IncludesResolveRelativeToTheIncludingFile) {
    const std::string dir = test::tempDir("LoaderInclude");
    fs::create_directories(dir + "/parts/more");
    test::writeFile(dir, "parts/defaults.xml", R"(<scene version="0.6.0">
  <default name="radius" value="2"/>
  <include filename="more/integrator.xml"/>
  <bsdf type="diffuse" id="white"/>
</scene>)");
    test::writeFile(dir, "parts/more/integrator.xml", R"(<scene version="0.5.0">
  <integrator type="path"><integer name="maxDepth" value="$radius"/></integrator>
</scene>)");
    const std::string main = test::writeFile(dir, "scene.xml", sceneXml(R"(
  <include filename="parts/defaults.xml"/>
  <shape type="sphere"><float name="radius" value="$radius"/><ref id="white"/></shape>)"));
    auto scene = loadScene(main);
    EXPECT_EQ(scene->integratorProperties().pluginName(), "path");
    EXPECT_EQ(scene->integratorProperties().getInt("maxDepth"), 2);
    ASSERT_EQ(scene->shapes().size(), 1u);
    EXPECT_NEAR(scene->shapes()[0]->bbox().extents().x, 4.0, 1e-9);
    EXPECT_EQ(scene->shapes()[0]->bsdf()->id(), "white");
}

TEST(Loader, RefsByIdShareObjectsAndNamedRefsFillSlots) {
    auto scene = load(R"(
  <bsdf type="diffuse" id="white"/>
  <texture type="checkerboard" id="checks"/>
  <bsdf type="diffuse" id="checked"><ref name="reflectance" id="checks"/></bsdf>
  <shape type="sphere"><ref id="white"/></shape>
  <shape type="sphere"><ref id="checked"/></shape>
  <shape type="sphere"><ref id="white"/></shape>)");
    ASSERT_EQ(scene->shapes().size(), 3u);
    EXPECT_EQ(scene->shapes()[0]->bsdf()->id(), "white");
    EXPECT_EQ(scene->shapes()[1]->bsdf()->id(), "checked");
    EXPECT_EQ(scene->shapes()[0]->bsdfPtr(), scene->shapes()[2]->bsdfPtr());

    // The name on a ref is the slot it fills: a misspelt slot leaves the texture unused.
    const std::string msg = loadError(R"(
  <texture type="checkerboard" id="checks"/>
  <shape type="sphere"><bsdf type="diffuse"><ref name="reflectanse" id="checks"/></bsdf></shape>)");
    EXPECT_NE(msg.find("named 'reflectanse' (id 'checks')"), std::string::npos) << msg;
}

TEST(Loader, NamedMediumRefsSetInteriorAndExterior) {
    auto scene = load(R"(
  <medium type="homogeneous" id="gas">
    <rgb name="sigmaA" value="0.1"/><rgb name="sigmaS" value="0.2"/>
    <phase type="hg"><float name="g" value="0.5"/></phase>
  </medium>
  <medium type="homogeneous" id="fog"><rgb name="sigmaA" value="0.01"/><rgb name="sigmaS" value="0.02"/></medium>
  <shape type="sphere">
    <ref name="interior" id="gas"/>
    <ref name="exterior" id="fog"/>
  </shape>)");
    ASSERT_EQ(scene->shapes().size(), 1u);
    ASSERT_NE(scene->shapes()[0]->interiorMedium(), nullptr);
    ASSERT_NE(scene->shapes()[0]->exteriorMedium(), nullptr);
    EXPECT_EQ(scene->shapes()[0]->interiorMedium()->id(), "gas");
    EXPECT_EQ(scene->shapes()[0]->exteriorMedium()->id(), "fog");
}

TEST(Loader, TransformElementsComposeInDocumentOrder) {
    auto scene = load(R"(
  <integrator type="path">
    <transform name="srt">
      <scale x="2" y="3" z="4"/>
      <rotate y="1" angle="90"/>
      <translate x="1" y="2" z="3"/>
    </transform>
    <transform name="translateThenLookAt">
      <translate x="1"/>
      <lookat origin="0, 0, 0" target="1, 0, 0" up="0, 1, 0"/>
    </transform>
    <transform name="matrixThenUniformScale">
      <matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>
      <scale value="2"/>
    </transform>
    <transform name="axisRotate"><rotate axis="0, 0, 1" angle="90"/></transform>
  </integrator>)");
    const Properties &p = scene->integratorProperties();
    // translate * rotate_y(90) * scale: rotate_y(90) maps x to -z and z to x.
    expectMatrixNear(p.getTransform("srt").matrix(), {{{0, 0, 4, 1}, {0, 3, 0, 2}, {-2, 0, 0, 3}, {0, 0, 0, 1}}});
    // lookAt * translate: Mitsuba's lookat has columns (left, up, dir, origin) = ((0,0,-1), (0,1,0), (1,0,0), 0).
    expectMatrixNear(p.getTransform("translateThenLookAt").matrix(),
                     {{{0, 0, 1, 0}, {0, 1, 0, 0}, {-1, 0, 0, -1}, {0, 0, 0, 1}}});
    expectMatrixNear(p.getTransform("matrixThenUniformScale").matrix(),
                     {{{2, 0, 0, 10}, {0, 2, 0, 12}, {0, 0, 2, 14}, {0, 0, 0, 1}}});
    expectMatrixNear(p.getTransform("axisRotate").matrix(),
                     {{{0, -1, 0, 0}, {1, 0, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}});
    // The cached inverse is consistent.
    const Transform t = p.getTransform("srt");
    const Vec3 q = t.inverse().point(t.point(Vec3(0.3, -0.7, 1.9)));
    EXPECT_NEAR(q.x, 0.3, 1e-12);
    EXPECT_NEAR(q.y, -0.7, 1e-12);
    EXPECT_NEAR(q.z, 1.9, 1e-12);
}

TEST(Loader, SpectraConvertThroughTheCieMatchingFunctions) {
    auto scene = load(R"(
  <integrator type="path">
    <spectrum name="flat" value="400:0.5, 500:0.5, 600:0.5, 700:0.5"/>
    <spectrum name="line610" value="600:0, 610:1, 620:0"/>
    <spectrum name="line450" value="440:0, 450:1, 460:0"/>
    <spectrum name="grey" value="0.25"/>
    <spectrum name="rgbMode" value="0.1, 0.2, 0.3"/>
    <blackbody name="bb" temperature="6500K"/>
    <blackbody name="bbScaled" temperature="6500" scale="2"/>
    <blackbody name="bb2000" temperature="2000K"/>
  </integrator>)");
    const Properties &p = scene->integratorProperties();
    // A constant spectrum (here over 400-700 nm only, losing the faint tails) is grey within 1%.
    expectSpectrumNear(p.getSpectrum("flat"), Spectrum(0.5), 0.005);
    // Narrow lines: 610 nm is saturated red, 450 nm blue.
    const Spectrum red = p.getSpectrum("line610"), blue = p.getSpectrum("line450");
    EXPECT_GT(red.r, 0.0);
    EXPECT_LT(red.g, 0.05 * red.r);
    EXPECT_LT(red.b, 0.05 * red.r);
    EXPECT_GT(blue.b, 0.0);
    EXPECT_LT(blue.r, 0.5 * blue.b);
    EXPECT_LT(blue.g, 0.5 * blue.b);
    expectSpectrumNear(p.getSpectrum("grey"), Spectrum(0.25), 0);
    expectSpectrumNear(p.getSpectrum("rgbMode"), Spectrum(0.1, 0.2, 0.3), 0);

    // 6500 K lies close to D65, the white of sRGB: the channels agree within 10%. Its luminance is
    // the y-bar-weighted mean of Planck's law per nm, near its value at 555 nm (42706 W m^-2 sr^-1 nm^-1).
    const Spectrum bb = p.getSpectrum("bb");
    EXPECT_LT(bb.max() / bb.min(), 1.1) << bb.r << " " << bb.g << " " << bb.b;
    EXPECT_NEAR(bb.luminance(), 42706.0, 0.05 * 42706.0);
    expectSpectrumNear(p.getSpectrum("bbScaled"), bb * 2.0, 1e-9 * bb.max());
    // 2000 K is candle-light orange.
    const Spectrum warm = p.getSpectrum("bb2000");
    EXPECT_GT(warm.r, 2.0 * warm.g);
    EXPECT_GT(warm.g, warm.b);
}

TEST(SpectrumConvert, EqualEnergyHasUnitLuminanceAndGreyRgb) {
    const Vec3 xyz = spectrumToXYZ({{380, 1.0}, {780, 1.0}});
    EXPECT_NEAR(xyz.y, 1.0, 1e-12);
    // Illuminant E has chromaticity (1/3, 1/3); the 5 nm table reproduces it to about 1e-3.
    EXPECT_NEAR(xyz.x / (xyz.x + xyz.y + xyz.z), 1.0 / 3.0, 2e-3);
    expectSpectrumNear(sampledSpectrumToRGB({{300, 0.7}, {900, 0.7}}), Spectrum(0.7), 1e-12);
    EXPECT_THROW(spectrumToXYZ({{500, 1.0}}), std::invalid_argument);
    EXPECT_THROW(spectrumToXYZ({{500, 1.0}, {500, 2.0}}), std::invalid_argument);
    EXPECT_THROW(blackbodyToRGB(-5), std::invalid_argument);
}

TEST(Loader, RgbHexAndSrgbDecode) {
    auto scene = load(R"(
  <integrator type="path">
    <rgb name="hex" value="#ff8000"/>
    <rgb name="grey" value="0.3"/>
    <srgb name="half" value="0.5, 0.5, 0.5"/>
    <srgb name="hexSrgb" value="#808080"/>
  </integrator>)");
    const Properties &p = scene->integratorProperties();
    expectSpectrumNear(p.getSpectrum("hex"), Spectrum(1.0, 128.0 / 255.0, 0.0), 1e-12);
    expectSpectrumNear(p.getSpectrum("grey"), Spectrum(0.3), 0);
    // IEC 61966-2-1 decoding: ((v + 0.055) / 1.055)^2.4.
    expectSpectrumNear(p.getSpectrum("half"), Spectrum(0.21404114048223255), 1e-12);
    expectSpectrumNear(p.getSpectrum("hexSrgb"), Spectrum(0.21586050011389926), 1e-12);
}

TEST(Loader, PointsVectorsNumbersAndBooleans) {
    auto scene = load(R"(
  <integrator type="path">
    <point name="p" x="1" y="-2.5" z="3e2"/>
    <vector name="v" value="4, 5, 6"/>
    <integer name="count" value="+12"/>
    <float name="f" value=" 0.25 "/>
    <boolean name="on" value="true"/>
  </integrator>)");
    const Properties &p = scene->integratorProperties();
    EXPECT_EQ(p.getPoint("p"), Vec3(1, -2.5, 300));
    EXPECT_EQ(p.getVector("v"), Vec3(4, 5, 6));
    EXPECT_EQ(p.getInt("count"), 12);
    EXPECT_EQ(p.getFloat("count"), 12.0);  // integers are accepted where floats are expected
    EXPECT_EQ(p.getFloat("f"), 0.25);
    EXPECT_TRUE(p.getBool("on"));
    EXPECT_THROW(p.getInt("f"), SceneError);  // but not the other way round
}

TEST(Loader, AcceptsMitsuba03To06AndRejectsMitsuba2And3) {
    for (const char *v : {"0.3.0", "0.4.0", "0.5.0", "0.6.0"}) EXPECT_NO_THROW(load("", {}, v)) << v;
    for (const char *v : {"2.0.0", "3.0.0"}) {
        try {
            load("", {}, v);
            ADD_FAILURE() << v << " loaded";
        } catch (const SceneError &e) {
            EXPECT_NE(std::string(e.what()).find("Mitsuba 2/3 syntax is not supported"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(load("", {}, "0.2.0"), SceneError);
    EXPECT_THROW(load("", {}, "zero"), SceneError);
}

TEST(Loader, NestedElementsAreCheckedLikeTopLevelOnes) {
    EXPECT_NE(loadError(R"(<shape type="sphere"><bsdf type="difuse"/></shape>)").find("unknown bsdf type 'difuse'"),
              std::string::npos);
    EXPECT_NE(loadError(R"(<shape type="sphere"><translate x="1"/></shape>)").find("only allowed inside <transform>"),
              std::string::npos);
    EXPECT_NE(loadError(R"(<film type="hdrfilm"/>)").find("must be nested"), std::string::npos);
    EXPECT_NE(loadError(R"(<bsdf type="diffuse"/>)").find("needs an 'id'"), std::string::npos);
    // A texture slot given both as a parameter and as a named child is a duplicate.
    EXPECT_NE(loadError(R"(<shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.5"/>
      <texture type="checkerboard" name="reflectance"/></bsdf></shape>)")
                  .find("duplicate parameter 'reflectance'"),
              std::string::npos);
}

TEST(Properties, GettersMarkUseAndReportTypeErrorsAtTheParameter) {
    Properties p(ObjectKind::Shape, "sphere", {"scene.xml", 3});
    p.set("radius", Properties::Type::Integer, int64_t(2), {"scene.xml", 4});
    p.set("center", Properties::Type::Point, Vec3(1, 2, 3), {"scene.xml", 5});
    p.set("label", Properties::Type::String, std::string("x"), {"scene.xml", 6});
    EXPECT_THROW(p.set("radius", Properties::Type::Float, 1.0, {"scene.xml", 7}), SceneError);
    EXPECT_EQ(p.getFloat("radius"), 2.0);
    EXPECT_EQ(p.getSpectrum("radius"), Spectrum(2.0));
    EXPECT_EQ(p.getPoint("center"), Vec3(1, 2, 3));
    EXPECT_EQ(p.getFloat("missing", 1.5), 1.5);
    try {
        p.checkAllUsed();
        ADD_FAILURE() << "unused 'label' not reported";
    } catch (const SceneError &e) {
        EXPECT_EQ(std::string(e.what()), "scene.xml:6: sphere: unknown parameter 'label'");
    }
    try {
        p.getBool("label");
        ADD_FAILURE() << "type mismatch not reported";
    } catch (const SceneError &e) {
        EXPECT_EQ(std::string(e.what()),
                  "scene.xml:6: sphere: parameter 'label': expected a boolean value but got a string");
    }
    EXPECT_NO_THROW(p.checkAllUsed());
    try {
        p.getFloat("width");
        ADD_FAILURE() << "missing parameter not reported";
    } catch (const SceneError &e) {
        EXPECT_EQ(std::string(e.what()), "scene.xml:3: sphere: missing parameter 'width'");
    }
}

TEST(Properties, GetTextureWrapsValuesOrReturnsTheNamedChild) {
    Properties p(ObjectKind::BSDF, "diffuse", {"scene.xml", 1});
    p.set("reflectance", Properties::Type::Float, 0.25, {"scene.xml", 2});
    auto child = std::make_shared<ConstantTexture>(Spectrum(0.1, 0.2, 0.3));
    p.addChild({"specular", ObjectKind::Texture, child, {"scene.xml", 3}});
    const auto wrapped = p.getTexture("reflectance");
    EXPECT_TRUE(wrapped->isConstant());
    EXPECT_EQ(wrapped->average(), Spectrum(0.25));
    EXPECT_EQ(p.getTexture("specular", Spectrum(1.0)), child);
    EXPECT_EQ(p.getTexture("absent", Spectrum(0.5))->average(), Spectrum(0.5));
    EXPECT_THROW(p.getTexture("absent"), SceneError);
    EXPECT_NO_THROW(p.checkAllUsed());
}

TEST(LoadContext, ResolvesInsideTheBundleOnly) {
    const std::string dir = test::tempDir("LoadContextResolve");
    fs::create_directories(dir + "/parts");
    test::writeFile(dir, "mesh.obj", "");
    test::writeFile(dir + "/..", "outside.obj", "");
    const LoadContext ctx{dir + "/parts", dir};
    auto resolve = [&](const std::string &name) {
        Properties p(ObjectKind::Shape, "obj", {"scene.xml", 1});
        p.set("filename", Properties::Type::String, name, {"scene.xml", 2});
        return ctx.resolve(p, "filename");
    };
    EXPECT_EQ(fs::path(resolve("../mesh.obj")), fs::path(dir) / "mesh.obj");
    EXPECT_EQ(fs::path(resolve("./../parts/../mesh.obj")), fs::path(dir) / "mesh.obj");
    EXPECT_THROW(resolve("../../outside.obj"), SceneError);
    EXPECT_THROW(resolve(fs::absolute(dir + "/mesh.obj").string()), SceneError);
    EXPECT_THROW(resolve("nothing.obj"), SceneError);
    EXPECT_THROW(resolve(""), SceneError);
    EXPECT_THROW(resolve("."), SceneError);  // a directory is not a file
}

TEST(SamplerSettings, SampleCountsRoundAsInMitsuba) {
    auto count = [](const std::string &type, int64_t requested) {
        Properties p(ObjectKind::Sampler, type, {"scene.xml", 1});
        p.set("sampleCount", Properties::Type::Integer, requested, {"scene.xml", 2});
        const PluginFactory *f = findPlugin(ObjectKind::Sampler, type);
        EXPECT_NE(f, nullptr) << type;
        auto obj = std::dynamic_pointer_cast<SamplerSettings>((*f)(p, LoadContext{}));
        p.checkAllUsed();
        return obj->sampleCount();
    };
    EXPECT_EQ(count("independent", 5), 5);
    EXPECT_EQ(count("stratified", 5), 9);  // next perfect square
    EXPECT_EQ(count("stratified", 16), 16);
    EXPECT_EQ(count("ldsampler", 5), 8);  // next power of two
    EXPECT_EQ(count("halton", 7), 7);
    EXPECT_EQ(count("hammersley", 7), 7);
    EXPECT_EQ(count("sobol", 3), 3);
    EXPECT_THROW(count("independent", 0), SceneError);
}

// `independent` draws independent numbers; the others one low-discrepancy sequence (core/ld_sampler.h),
// stratified in every request (halton, hammersley, sobol) or in the first `dimension` 1D and 2D requests
// (stratified, ldsampler, default 4 as in Mitsuba).
TEST(SamplerSettings, TypesChooseTheSequence) {
    auto sequence = [](const std::string &type, int64_t dimension) {
        Properties p(ObjectKind::Sampler, type, {"scene.xml", 1});
        if (dimension != 0) p.set("dimension", Properties::Type::Integer, dimension, {"scene.xml", 2});
        auto obj =
            std::dynamic_pointer_cast<SamplerSettings>((*findPlugin(ObjectKind::Sampler, type))(p, LoadContext{}));
        p.checkAllUsed();
        return std::make_pair(obj->sequence().lowDiscrepancy, obj->sequence().dimension);
    };
    EXPECT_EQ(sequence("independent", 0), std::make_pair(false, 0));
    EXPECT_EQ(sequence("stratified", 0), std::make_pair(true, 4));
    EXPECT_EQ(sequence("ldsampler", 0), std::make_pair(true, 4));
    EXPECT_EQ(sequence("ldsampler", 7), std::make_pair(true, 7));
    EXPECT_EQ(sequence("halton", 0), std::make_pair(true, 0));
    EXPECT_EQ(sequence("hammersley", 0), std::make_pair(true, 0));
    EXPECT_EQ(sequence("sobol", 0), std::make_pair(true, 0));
    try {
        sequence("ldsampler", -2);
        ADD_FAILURE() << "a negative dimension was accepted";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("dimension"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("scene.xml"), std::string::npos) << e.what();
    }
}

// `sobol`'s `layout`: "pixel" (the default) keeps the padded sequence, "image" takes one Sobol sequence through the
// image (core/global_sobol_sampler.h); another value is an error naming the parameter and the file.
TEST(SamplerSettings, SobolLayoutChoosesTheGlobalSequence) {
    auto acrossPixels = [](const std::string &layout) {
        Properties p(ObjectKind::Sampler, "sobol", {"scene.xml", 1});
        if (!layout.empty()) p.set("layout", Properties::Type::String, layout, {"scene.xml", 2});
        auto obj =
            std::dynamic_pointer_cast<SamplerSettings>((*findPlugin(ObjectKind::Sampler, "sobol"))(p, LoadContext{}));
        p.checkAllUsed();
        EXPECT_TRUE(obj->sequence().lowDiscrepancy);
        return obj->sequence().acrossPixels;
    };
    EXPECT_FALSE(acrossPixels(""));
    EXPECT_FALSE(acrossPixels("pixel"));
    EXPECT_TRUE(acrossPixels("image"));
    try {
        acrossPixels("tiles");
        ADD_FAILURE() << "layout \"tiles\" was accepted";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("layout"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("scene.xml:2"), std::string::npos) << e.what();
    }
}

// Every scene shipped under scenes/ loads (each needs the shape, BSDF, emitter, medium and sensor
// plugins of the other modules).
std::vector<std::string> shippedScenes() {
    std::vector<std::string> files;
    for (const auto &dir : fs::directory_iterator(std::string(PATHFARM_SOURCE_DIR) + "/scenes"))
        if (dir.is_directory())
            for (const auto &f : fs::directory_iterator(dir.path()))
                if (f.path().extension() == ".xml") files.push_back(f.path().string());
    std::sort(files.begin(), files.end());
    return files;
}

class ShippedScene : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedScene, Loads) {
    std::unique_ptr<Scene> scene;
    try {
        scene = loadScene(GetParam());
    } catch (const SceneError &e) {
        FAIL() << e.what();
    }
    EXPECT_FALSE(scene->shapes().empty());
    EXPECT_FALSE(scene->emitters().empty());
    EXPECT_GT(scene->sensor().film().width(), 0);
}

INSTANTIATE_TEST_SUITE_P(Scenes, ShippedScene, ::testing::ValuesIn(shippedScenes()),
                         [](const ::testing::TestParamInfo<std::string> &info) {
                             const fs::path p(info.param);
                             std::string name = p.parent_path().filename().string() + "_" + p.stem().string();
                             for (char &c : name)
                                 if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                             return name;
                         });

}  // namespace
}  // namespace pf
