// Textures: bitmap lookups (nearest and bilinear), wrap modes, uv transform, gamma/sRGB decoding,
// channels, exact gradients, parameter errors; checkerboard and scale; the default finite-difference
// gradient of the Texture base class.
#include <gtest/gtest.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>

#include "core/rng.h"
#include "image/bitmap.h"
#include "scene/plugins.h"
#include "texture/texture.h"

namespace pf {
namespace {

namespace fs = std::filesystem;

// A 4x3 image with distinct, exactly representable texels: R = x + 1, G = 10 (y + 1), B = (x + 4y) / 16.
Spectrum texelValue(int x, int y) { return {x + 1.0, 10.0 * (y + 1), (x + 4.0 * y) / 16.0}; }

class TextureTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() / ("pathfarm_test_texture_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        Bitmap img(4, 3);
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x) img.set(x, y, texelValue(x, y));
        writeEXR((dir_ / "grid.exr").string(), img);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }

    struct Params {
        Properties props;
        explicit Params(const std::string &type = "bitmap")
            : props(ObjectKind::Texture, type, SourceLocation{"scene.xml", 20}) {}
        Params &str(const std::string &n, const std::string &v) {
            props.set(n, Properties::Type::String, v, {"scene.xml", 21});
            return *this;
        }
        Params &real(const std::string &n, double v) {
            props.set(n, Properties::Type::Float, v, {"scene.xml", 22});
            return *this;
        }
    };

    std::shared_ptr<Texture> make(const std::string &type, const Params &p) const {
        const PluginFactory *f = findPlugin(ObjectKind::Texture, type);
        if (!f) throw std::runtime_error("no texture plugin " + type);
        const std::string dir = dir_.string();
        auto tex = std::dynamic_pointer_cast<Texture>((*f)(p.props, LoadContext{dir, dir}));
        p.props.checkAllUsed();
        return tex;
    }
    std::shared_ptr<Texture> bitmap(Params p, const std::string &file = "grid.exr") const {
        return make("bitmap", p.str("filename", file));
    }
    std::string file(const std::string &name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

Spectrum at(const Texture &t, double u, double v) {
    Intersection its;
    its.uv = Vec2(u, v);
    return t.eval(its);
}

void expectNear(const Spectrum &a, const Spectrum &b, double tol, const std::string &what = "") {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], tol * (1 + std::abs(b[k]))) << what << " channel " << k;
}

// Expects `fn` to throw a SceneError whose message contains `needle`.
void expectSceneError(const std::function<void()> &fn, const std::string &needle) {
    try {
        fn();
        ADD_FAILURE() << "no SceneError; expected one mentioning " << needle;
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

TEST_F(TextureTest, LookupsHitTexelCentresAndInterpolate) {
    const auto nearest = bitmap(Params().str("filterType", "nearest"));
    const auto bilinear = bitmap(Params());  // default "ewa" means bilinear here
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) {
            const double u = (x + 0.5) / 4, v = (y + 0.5) / 3;
            EXPECT_EQ(at(*nearest, u, v), texelValue(x, y));
            expectNear(at(*bilinear, u, v), texelValue(x, y), 1e-15);
            // Anywhere inside the texel, nearest returns the same value.
            EXPECT_EQ(at(*nearest, (x + 0.01) / 4, (y + 0.99) / 3), texelValue(x, y));
        }
    // Halfway between texel centres: the mean of the neighbours; a quarter of the way: 3:1 weights.
    expectNear(at(*bilinear, 2.0 / 4, 1.5 / 3), (texelValue(1, 1) + texelValue(2, 1)) * 0.5, 1e-15);
    expectNear(at(*bilinear, 1.5 / 4, 2.0 / 3), (texelValue(1, 1) + texelValue(1, 2)) * 0.5, 1e-15);
    expectNear(at(*bilinear, 1.75 / 4, 1.5 / 3), texelValue(1, 1) * 0.75 + texelValue(2, 1) * 0.25, 1e-15);
    for (const char *f : {"trilinear", "bilinear", "EWA"})
        EXPECT_EQ(at(*bitmap(Params().str("filterType", f)), 0.3, 0.7), at(*bilinear, 0.3, 0.7)) << f;

    // Mean and maximum over the texels.
    Spectrum sum(0.0);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) sum += texelValue(x, y);
    expectNear(bilinear->average(), sum / 12.0, 1e-15);
    EXPECT_EQ(bilinear->maximum(), texelValue(3, 2));
    EXPECT_FALSE(bilinear->isConstant());
}

TEST_F(TextureTest, WrapModes) {
    const auto repeat = bitmap(Params().str("filterType", "nearest"));
    const auto mirror = bitmap(Params().str("filterType", "nearest").str("wrapMode", "mirror"));
    const auto clampT = bitmap(Params().str("filterType", "nearest").str("wrapMode", "clamp"));
    const auto zero = bitmap(Params().str("filterType", "nearest").str("wrapMode", "zero"));
    const auto one = bitmap(Params().str("filterType", "nearest").str("wrapMode", "one"));
    const double v = 1.5 / 3;  // row 1
    // Texel column -1 (u in [-1/4, 0)) and column 4 (u in [1, 5/4)).
    EXPECT_EQ(at(*repeat, -0.1, v), texelValue(3, 1));
    EXPECT_EQ(at(*repeat, 1.1, v), texelValue(0, 1));
    EXPECT_EQ(at(*repeat, 7.3, v), at(*repeat, 0.3, v));
    EXPECT_EQ(at(*repeat, -7.7, v), at(*repeat, 0.3, v));
    EXPECT_EQ(at(*mirror, -0.1, v), texelValue(0, 1));
    EXPECT_EQ(at(*mirror, -0.3, v), texelValue(1, 1));
    EXPECT_EQ(at(*mirror, 1.1, v), texelValue(3, 1));
    EXPECT_EQ(at(*mirror, 1.9, v), texelValue(0, 1));
    EXPECT_EQ(at(*mirror, 2.1, v), texelValue(0, 1));  // period 2
    EXPECT_EQ(at(*clampT, -5.0, v), texelValue(0, 1));
    EXPECT_EQ(at(*clampT, 5.0, 5.0), texelValue(3, 2));
    EXPECT_EQ(at(*zero, -0.1, v), Spectrum(0.0));
    EXPECT_EQ(at(*zero, 0.5, 1.2), Spectrum(0.0));
    EXPECT_EQ(at(*zero, 0.1, v), texelValue(0, 1));
    EXPECT_EQ(at(*one, 1.1, v), Spectrum(1.0));
    EXPECT_EQ(at(*one, 0.1, -0.01), Spectrum(1.0));

    // Separate modes per axis, and Mitsuba's aliases black/white.
    const auto mixed =
        bitmap(Params().str("filterType", "nearest").str("wrapModeU", "clamp").str("wrapModeV", "white"));
    EXPECT_EQ(at(*mixed, -3.0, v), texelValue(0, 1));
    EXPECT_EQ(at(*mixed, 0.1, 1.5), Spectrum(1.0));
    const auto black = bitmap(Params().str("filterType", "nearest").str("wrapMode", "black"));
    EXPECT_EQ(at(*black, 2.0, v), Spectrum(0.0));

    // Bilinear lookups blend across the edge with the wrapped neighbour: at u = 0 (halfway between
    // texel centres -1 and 0) repeat mixes columns 3 and 0, mirror sees column 0 twice, zero fades.
    const auto bRepeat = bitmap(Params());
    const auto bMirror = bitmap(Params().str("wrapMode", "mirror"));
    const auto bZero = bitmap(Params().str("wrapMode", "zero"));
    expectNear(at(*bRepeat, 0.0, v), (texelValue(3, 1) + texelValue(0, 1)) * 0.5, 1e-15);
    expectNear(at(*bMirror, 0.0, v), texelValue(0, 1), 1e-15);
    expectNear(at(*bZero, 0.0, v), texelValue(0, 1) * 0.5, 1e-15);
    // Mirror is symmetric about the edges.
    for (double u : {0.05, 0.2, 0.37}) expectNear(at(*bMirror, -u, 0.3), at(*bMirror, u, 0.3), 1e-14, "mirror");
    // Non-finite uv gives black (Mitsuba), huge uv stays defined.
    EXPECT_EQ(at(*bRepeat, NAN, 0.5), Spectrum(0.0));
    EXPECT_TRUE(at(*bRepeat, 1e300, -1e300).isFinite());
}

TEST_F(TextureTest, UvScaleAndOffset) {
    const auto base = bitmap(Params());
    const auto moved =
        bitmap(Params().real("uscale", 2.0).real("vscale", -0.5).real("uoffset", 0.25).real("voffset", 0.1));
    PCG32 rng(4, 2);
    for (int i = 0; i < 50; ++i) {
        const double u = rng.nextDouble(), v = rng.nextDouble();
        EXPECT_EQ(at(*moved, u, v), at(*base, 2.0 * u + 0.25, -0.5 * v + 0.1));
    }
}

TEST_F(TextureTest, GammaAndSrgbDecoding) {
    const unsigned char px[6] = {0, 128, 255, 10, 200, 64};
    ASSERT_TRUE(stbi_write_png(file("bytes.png").c_str(), 2, 1, 3, px, 6));
    const auto srgb = bitmap(Params().str("filterType", "nearest"), "bytes.png");
    const auto linear = bitmap(Params().str("filterType", "nearest").real("gamma", 1.0), "bytes.png");
    const auto power = bitmap(Params().str("filterType", "nearest").real("gamma", 2.2), "bytes.png");
    const auto explicitSrgb = bitmap(Params().str("filterType", "nearest").real("gamma", -1.0), "bytes.png");
    for (int x = 0; x < 2; ++x)
        for (int c = 0; c < 3; ++c) {
            const double b = px[3 * x + c] / 255.0;
            // Texels are stored as float.
            EXPECT_FLOAT_EQ(at(*srgb, (x + 0.5) / 2, 0.5)[c], static_cast<float>(srgbToLinear(b)));
            EXPECT_FLOAT_EQ(at(*explicitSrgb, (x + 0.5) / 2, 0.5)[c], static_cast<float>(srgbToLinear(b)));
            EXPECT_FLOAT_EQ(at(*linear, (x + 0.5) / 2, 0.5)[c], static_cast<float>(b));
            EXPECT_FLOAT_EQ(at(*power, (x + 0.5) / 2, 0.5)[c],
                            static_cast<float>(std::pow(static_cast<float>(b), 2.2)));
        }
    // EXR data is linear by default; a gamma override applies to it too.
    const auto exr = bitmap(Params().str("filterType", "nearest"));
    const auto exrSquared = bitmap(Params().str("filterType", "nearest").real("gamma", 2.0));
    EXPECT_EQ(at(*exr, 0.6, 0.1), texelValue(2, 0));
    expectNear(at(*exrSquared, 0.6, 0.1), texelValue(2, 0) * texelValue(2, 0), 1e-7);
}

TEST_F(TextureTest, SingleChannel) {
    const auto g = bitmap(Params().str("filterType", "nearest").str("channel", "g"));
    const auto b = bitmap(Params().str("filterType", "nearest").str("channel", "B"));
    EXPECT_EQ(at(*g, 0.6, 0.9), Spectrum(texelValue(2, 2).g));
    EXPECT_EQ(at(*b, 0.6, 0.9), Spectrum(texelValue(2, 2).b));
}

TEST_F(TextureTest, BilinearGradientIsExact) {
    const auto tex = bitmap(Params().real("uscale", 1.5).real("vscale", 0.75).real("uoffset", 0.1));
    PCG32 rng(8, 3);
    const double h = 1e-6;
    int checked = 0;
    for (int i = 0; i < 200; ++i) {
        Intersection its;
        its.uv = Vec2(rng.nextDouble() * 2 - 0.5, rng.nextDouble() * 2 - 0.5);
        // Central differences of a bilinear function are exact within one texel cell; skip points
        // whose stencil crosses a line through texel centres, where the interpolant has a kink.
        const double x = (its.uv.x * 1.5 + 0.1) * 4 - 0.5, y = (its.uv.y * 0.75) * 3 - 0.5;
        if (std::floor(x - 1.5 * 4 * h) != std::floor(x + 1.5 * 4 * h) ||
            std::floor(y - 0.75 * 3 * h) != std::floor(y + 0.75 * 3 * h))
            continue;
        Spectrum du, dv;
        tex->evalGradient(its, du, dv);
        const Spectrum fdU = (at(*tex, its.uv.x + h, its.uv.y) - at(*tex, its.uv.x - h, its.uv.y)) / (2 * h);
        const Spectrum fdV = (at(*tex, its.uv.x, its.uv.y + h) - at(*tex, its.uv.x, its.uv.y - h)) / (2 * h);
        expectNear(du, fdU, 1e-6, "d/du");
        expectNear(dv, fdV, 1e-6, "d/dv");
        ++checked;
    }
    EXPECT_GT(checked, 150);
    // A non-trivial gradient: along u in row 0 the red channel rises by 1 per texel, i.e. by
    // 4 per unit of the texture's u and 6 per unit of the surface's u (uscale 1.5).
    Intersection its;
    its.uv = Vec2(((1.2 / 4) - 0.1) / 1.5, (0.5 / 3) / 0.75);
    Spectrum du, dv;
    tex->evalGradient(its, du, dv);
    EXPECT_NEAR(du.r, 6.0, 1e-12);
    EXPECT_NEAR(dv.g, 10.0 * 3 * 0.75, 1e-9);

    const auto nearest = bitmap(Params().str("filterType", "nearest"));
    nearest->evalGradient(its, du, dv);
    EXPECT_TRUE(du.isBlack() && dv.isBlack());
}

TEST_F(TextureTest, BadBitmapParameters) {
    expectSceneError([&] { bitmap(Params(), "missing.png"); }, "'filename'");
    std::ofstream(file("broken.png")) << "\x89PNG\r\n\x1a\nnot really";
    expectSceneError([&] { bitmap(Params(), "broken.png"); }, "broken.png");
    std::ofstream(file("broken.exr")) << "v/1\x01 nope";
    expectSceneError([&] { bitmap(Params(), "broken.exr"); }, "broken.exr");
    expectSceneError([&] { bitmap(Params().str("filterType", "cubic")); }, "'filterType'");
    expectSceneError([&] { bitmap(Params().str("wrapMode", "wrap")); }, "'wrapMode'");
    expectSceneError([&] { bitmap(Params().str("wrapModeV", "tile")); }, "'wrapModeV'");
    expectSceneError([&] { bitmap(Params().str("channel", "a")); }, "'channel'");
    expectSceneError([&] { bitmap(Params().real("gamma", 0.0)); }, "'gamma'");
    expectSceneError([&] { bitmap(Params().real("gamma", -2.0)); }, "'gamma'");
    expectSceneError([&] { bitmap(Params().real("uscale", NAN)); }, "'uscale'");
    expectSceneError([&] { bitmap(Params().real("shininess", 1.0)); }, "'shininess'");
    // Accepted and ignored: MIP-map options.
    EXPECT_NO_THROW(bitmap(Params().real("maxAnisotropy", 8.0)));
}

TEST_F(TextureTest, Checkerboard) {
    const auto cb = make("checkerboard", Params("checkerboard"));
    EXPECT_EQ(at(*cb, 0.1, 0.1), Spectrum(0.4));
    EXPECT_EQ(at(*cb, 0.6, 0.1), Spectrum(0.2));
    EXPECT_EQ(at(*cb, 0.1, 0.6), Spectrum(0.2));
    EXPECT_EQ(at(*cb, 0.6, 0.6), Spectrum(0.4));
    EXPECT_EQ(at(*cb, 1.1, 0.1), Spectrum(0.4));
    EXPECT_EQ(at(*cb, 1.6, 2.2), Spectrum(0.2));
    // Mitsuba truncates towards zero: (-0.4, 0.1) lies in the same square as (0.1, 0.1), (-0.6, 0.1)
    // in the next one.
    EXPECT_EQ(at(*cb, -0.4, 0.1), Spectrum(0.4));
    EXPECT_EQ(at(*cb, -0.6, 0.1), Spectrum(0.2));
    EXPECT_EQ(at(*cb, -0.6, -0.6), Spectrum(0.4));
    EXPECT_TRUE(at(*cb, 1e300, 3e9).isFinite());
    expectNear(cb->average(), Spectrum(0.3), 1e-15);
    EXPECT_EQ(cb->maximum(), Spectrum(0.4));

    Params p("checkerboard");
    p.props.set("color0", Properties::Type::Spectrum, Spectrum(1, 0, 0), {"scene.xml", 23});
    p.props.set("color1", Properties::Type::Spectrum, Spectrum(0, 0.5, 2), {"scene.xml", 24});
    p.real("uscale", 4.0).real("uoffset", 0.5);
    const auto custom = make("checkerboard", p);
    // u' = 4 u + 0.5: u = 0.05 -> 0.7 (second square), u = 0.2 -> 1.3 (third).
    EXPECT_EQ(at(*custom, 0.05, 0.1), Spectrum(0, 0.5, 2));
    EXPECT_EQ(at(*custom, 0.2, 0.1), Spectrum(1, 0, 0));
    EXPECT_EQ(custom->maximum(), Spectrum(1, 0.5, 2));
}

TEST_F(TextureTest, ScaleTexture) {
    Params p("scale");
    p.real("scale", 2.0);
    p.props.addChild({"", ObjectKind::Texture, make("checkerboard", Params("checkerboard")), {"scene.xml", 25}});
    const auto scaled = make("scale", p);
    EXPECT_EQ(at(*scaled, 0.1, 0.1), Spectrum(0.8));
    EXPECT_EQ(at(*scaled, 0.6, 0.1), Spectrum(0.4));
    expectNear(scaled->average(), Spectrum(0.6), 1e-15);
    EXPECT_EQ(scaled->maximum(), Spectrum(0.8));
    EXPECT_FALSE(scaled->isConstant());

    Params ps("scale");
    ps.props.set("scale", Properties::Type::Spectrum, Spectrum(1, 2, 3), {"scene.xml", 26});
    ps.props.addChild({"value", ObjectKind::Texture, bitmap(Params()), {"scene.xml", 27}});
    const auto tinted = make("scale", ps);
    EXPECT_EQ(at(*tinted, 0.6, 0.1), at(*bitmap(Params()), 0.6, 0.1) * Spectrum(1, 2, 3));
    Intersection its;
    its.uv = Vec2(0.31, 0.4);
    Spectrum du, dv, du0, dv0;
    tinted->evalGradient(its, du, dv);
    bitmap(Params())->evalGradient(its, du0, dv0);
    EXPECT_EQ(du, du0 * Spectrum(1, 2, 3));
    EXPECT_EQ(dv, dv0 * Spectrum(1, 2, 3));

    Params pv("scale");
    pv.real("value", 0.25).real("scale", 3.0);
    const auto constant = make("scale", pv);
    EXPECT_TRUE(constant->isConstant());
    EXPECT_EQ(at(*constant, 0.9, 0.9), Spectrum(0.75));

    expectSceneError([&] { make("scale", Params("scale").real("scale", 2.0)); }, "nested texture");
    expectSceneError([&] { make("scale", Params("scale").real("value", 1.0).real("scale", -1.0)); }, "'scale'");
    Params both("scale");
    both.real("value", 1.0);
    both.props.addChild({"", ObjectKind::Texture, make("checkerboard", Params("checkerboard")), {"scene.xml", 28}});
    expectSceneError([&] { make("scale", both); }, "'value'");
}

// A smooth texture for the base class's central-difference gradient: f = (sin u * v^2, e^u, u v).
class SmoothTexture final : public Texture {
public:
    Spectrum eval(const Intersection &its) const override {
        const double u = its.uv.x, v = its.uv.y;
        return {std::sin(u) * v * v, std::exp(u), u * v};
    }
    Spectrum average() const override { return Spectrum(0.0); }
    Spectrum maximum() const override { return Spectrum(0.0); }
};

TEST(TextureBase, DefaultGradientIsCentralDifferences) {
    const SmoothTexture t;
    PCG32 rng(12, 5);
    for (int i = 0; i < 20; ++i) {
        Intersection its;
        its.uv = Vec2(rng.nextDouble() * 4 - 2, rng.nextDouble() * 4 - 2);
        const double u = its.uv.x, v = its.uv.y;
        Spectrum du, dv;
        t.evalGradient(its, du, dv);
        // Truncation error of central differences with h = 1e-3: f''' h^2 / 6, below 1e-6 here.
        expectNear(du, Spectrum(std::cos(u) * v * v, std::exp(u), v), 2e-6, "d/du");
        expectNear(dv, Spectrum(2 * std::sin(u) * v, 0.0, u), 2e-6, "d/dv");
    }
    // Constant textures have zero gradient.
    const ConstantTexture c(Spectrum(0.7));
    Intersection its;
    Spectrum du(1.0), dv(1.0);
    c.evalGradient(its, du, dv);
    EXPECT_TRUE(du.isBlack() && dv.isBlack());
}

}  // namespace
}  // namespace pf
