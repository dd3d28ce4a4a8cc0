// Film and texture file options read back from the files written: hdrfilm's pixelFormat and
// componentFormat in the EXR (OpenEXR's header and pixels), ldrfilm's tone mapping (gamma with exposure,
// sRGB, Reinhard's operator with key and burn) and pixelFormat in the PNG (stb), `pathfarm render`
// honouring both; Radiance RGBE (.hdr), BMP and Targa files written by stb_image_write as `bitmap`
// textures and `envmap` maps, and damaged ones refused with an error naming the file.
#include <ImfChannelList.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <gtest/gtest.h>
#include <stb_image_write.h>

#include <cmath>
#include <fstream>
#include <functional>

#include "core/error.h"
#include "emitter/emitter.h"
#include "image/bitmap.h"
#include "image/film.h"
#include "image/tonemap.h"
#include "scene/plugins.h"
#include "support/process.h"
#include "support/render_util.h"
#include "texture/texture.h"

namespace pf::test {
namespace {

// A 3 x 2 image of distinct values, one above 1 and one black.
Bitmap testImage() {
    Bitmap img(3, 2);
    img.set(0, 0, {0.5, 0.25, 0.125});
    img.set(1, 0, {1.0, 2.0, 4.0});
    img.set(2, 0, {0.0, 0.0, 0.0});
    img.set(0, 1, {0.75, 0.1, 0.3});
    img.set(1, 1, {0.02, 0.04, 0.06});
    img.set(2, 1, {3.0, 1.5, 0.5});
    return img;
}

// The message of the SceneError that `fn` throws ("" if none).
std::string sceneErrorOf(const std::function<void()> &fn) {
    try {
        fn();
    } catch (const SceneError &e) {
        return e.what();
    }
    return "";
}

// The channels of an EXR file, name and pixel type.
std::vector<std::pair<std::string, Imf::PixelType>> channelsOf(const std::string &path) {
    Imf::InputFile file(path.c_str());
    std::vector<std::pair<std::string, Imf::PixelType>> out;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
        out.push_back({it.name(), it.channel().type});
    return out;
}

TEST(ExrFormats, PixelAndComponentFormatsRoundTrip) {
    const std::string dir = tempDir("image-formats-exr");
    const Bitmap img = testImage();
    struct Case {
        PixelFormat pixels;
        ComponentFormat component;
        std::vector<std::string> names;
    };
    for (const Case &c : {Case{PixelFormat::RGB, ComponentFormat::Float32, {"B", "G", "R"}},
                          Case{PixelFormat::RGB, ComponentFormat::Float16, {"B", "G", "R"}},
                          Case{PixelFormat::RGBA, ComponentFormat::Float32, {"A", "B", "G", "R"}},
                          Case{PixelFormat::Luminance, ComponentFormat::Float16, {"Y"}},
                          Case{PixelFormat::LuminanceAlpha, ComponentFormat::Float32, {"A", "Y"}}}) {
        const std::string path = dir + "/out.exr";
        writeEXR(path, img, {c.pixels, c.component});
        const auto channels = channelsOf(path);
        ASSERT_EQ(channels.size(), c.names.size());  // OpenEXR lists channels by name
        const bool half = c.component == ComponentFormat::Float16;
        for (size_t i = 0; i < channels.size(); ++i) {
            EXPECT_EQ(channels[i].first, c.names[i]);
            EXPECT_EQ(channels[i].second, half ? Imf::HALF : Imf::FLOAT) << c.names[i];
        }
        const Bitmap back = readEXR(path);
        const bool grey = c.pixels == PixelFormat::Luminance || c.pixels == PixelFormat::LuminanceAlpha;
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 3; ++x)
                for (int k = 0; k < 3; ++k) {
                    const double v = grey ? img.get(x, y).luminance() : img.get(x, y)[k];
                    // float32 is exact; half keeps 11 significant bits.
                    EXPECT_NEAR(back.get(x, y)[k], v, half ? v * 4.9e-4 + 1e-7 : v * 6e-8) << x << "," << y << "," << k;
                }
        if (c.pixels == PixelFormat::RGBA) {
            Imf::InputFile file(path.c_str());
            EXPECT_TRUE(file.header().channels().findChannel("A"));
        }
    }
}

// 8-bit codes of a PNG read back with stb, channel c of pixel (x, y) of an n-channel image.
std::vector<int> pngCodes(const std::string &path) {
    const Bitmap raw = readLDR(path, false);
    std::vector<int> codes;
    for (float v : raw.rgb) codes.push_back(static_cast<int>(std::lround(v * 255)));
    return codes;
}

// The channels of a PNG from its IHDR colour type (byte 25): grey 0, grey + alpha 4, RGB 2, RGBA 6.
int pngChannels(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (data.size() < 26) return 0;
    switch (data[25]) {
        case 0:
            return 1;
        case 4:
            return 2;
        case 2:
            return 3;
        case 6:
            return 4;
        default:
            return 0;
    }
}

int code(double display) { return static_cast<int>(std::lround(std::clamp(display, 0.0, 1.0) * 255)); }

TEST(PngToneMapping, GammaExposureAndSrgb) {
    const std::string dir = tempDir("image-formats-png");
    const Bitmap img = testImage();
    ToneMap t;
    t.exposure = 1;
    t.gamma = 2.2;
    writePNG(dir + "/g.png", img, t);
    const std::vector<int> g = pngCodes(dir + "/g.png");
    for (size_t i = 0; i < img.rgb.size(); ++i) EXPECT_EQ(g[i], code(std::pow(img.rgb[i] * 2.0, 1 / 2.2))) << i;
    t.exposure = -1;
    t.gamma = -1;
    writePNG(dir + "/s.png", img, t);
    const std::vector<int> s = pngCodes(dir + "/s.png");
    for (size_t i = 0; i < img.rgb.size(); ++i)
        EXPECT_EQ(s[i], code(linearToSrgb(std::min(img.rgb[i] * 0.5, 1.0)))) << i;
}

// Reinhard et al. 2002 eqs. 1-4, written out for the test image: log-average luminance, key, white point.
std::vector<double> reinhard(const Bitmap &img, double key, double burn) {
    double logSum = 0, maxL = 0;
    const int n = img.width * img.height;
    for (int p = 0; p < n; ++p) {
        const double l = img.get(p % img.width, p / img.width).luminance();
        logSum += std::log(1e-4 + l);
        maxL = std::max(maxL, l);
    }
    const double a = key / std::exp(logSum / n), white = a * maxL * std::max(1 - burn, 1e-3);
    std::vector<double> out;
    for (int p = 0; p < n; ++p) {
        const Spectrum c = img.get(p % img.width, p / img.width);
        const double lw = c.luminance(), l = a * lw, ld = l * (1 + l / (white * white)) / (1 + l);
        for (int k = 0; k < 3; ++k) out.push_back(lw > 0 ? c[k] * ld / lw : 0.0);
    }
    return out;
}

TEST(PngToneMapping, ReinhardWithKeyAndBurn) {
    const std::string dir = tempDir("image-formats-reinhard");
    const Bitmap img = testImage();
    for (const auto &[key, burn] : {std::pair{0.18, 0.0}, std::pair{0.5, 0.0}, std::pair{0.18, 0.6}}) {
        ToneMap t;
        t.method = ToneMap::Method::Reinhard;
        t.key = key;
        t.burn = burn;
        t.gamma = 1.0;   // linear display values, so that the codes show the operator itself
        t.exposure = 3;  // not used by Reinhard's operator
        writePNG(dir + "/r.png", img, t);
        const std::vector<int> codes = pngCodes(dir + "/r.png");
        const std::vector<double> expected = reinhard(img, key, burn);
        for (size_t i = 0; i < codes.size(); ++i)
            EXPECT_EQ(codes[i], code(expected[i])) << key << " " << burn << " " << i;
    }
    // On a grey image: with burn = 0 the brightest pixel maps exactly to white and nothing else does; a
    // higher key brightens every other pixel (the white point follows the key).
    Bitmap grey(3, 2);
    for (int p = 0; p < 6; ++p) grey.set(p % 3, p / 3, Spectrum(img.get(p % 3, p / 3).luminance()));
    ToneMap t;
    t.method = ToneMap::Method::Reinhard;
    t.gamma = 1.0;
    const std::vector<double> display = toneMap(grey, t);
    ToneMap high = t;
    high.key = 0.5;
    const std::vector<double> brighter = toneMap(grey, high);
    EXPECT_NEAR(display[3], 1.0, 1e-12) << "pixel (1, 0) is the brightest";
    EXPECT_NEAR(brighter[3], 1.0, 1e-12);
    for (size_t i = 0; i < display.size(); ++i) {
        if (i / 3 == 1) continue;
        EXPECT_LT(display[i], 1.0) << i;
        if (display[i] > 0) {
            EXPECT_GT(brighter[i], display[i]) << i;
        }
    }
}

TEST(PngToneMapping, InvalidSettingsNameTheFile) {
    const std::string dir = tempDir("image-formats-png-invalid");
    for (const auto &[key, burn] : {std::pair{0.0, 0.0}, std::pair{0.18, 1.5}, std::pair{0.18, -0.1}}) {
        ToneMap t;
        t.method = ToneMap::Method::Reinhard;
        t.key = key;
        t.burn = burn;
        EXPECT_NE(sceneErrorOf([&] { writePNG(dir + "/bad.png", testImage(), t); }).find("bad.png"), std::string::npos);
    }
}

TEST(PngToneMapping, PixelFormats) {
    const std::string dir = tempDir("image-formats-png-pixels");
    const Bitmap img = testImage();
    ToneMap t;
    t.gamma = 1.0;
    for (const auto &[format, channels] :
         {std::pair{PixelFormat::Luminance, 1}, std::pair{PixelFormat::LuminanceAlpha, 2},
          std::pair{PixelFormat::RGBA, 4}, std::pair{PixelFormat::RGB, 3}}) {
        const std::string path = dir + "/p.png";
        writePNG(path, img, t, format);
        EXPECT_EQ(pngChannels(path), channels);
        const std::vector<int> codes = pngCodes(path);  // stb expands grey to r = g = b
        for (int p = 0; p < 6; ++p) {
            const Spectrum c = img.get(p % 3, p / 3);
            for (int k = 0; k < 3; ++k)
                EXPECT_EQ(codes[3 * p + k], code(channels <= 2 ? c.luminance() : c[k])) << channels << " " << p;
        }
    }
}

// A scene with an ldrfilm or an hdrfilm of the given parameters, rendered by `pathfarm render`.
const char *kScene = R"(<scene version="0.6.0">
  <integrator type="path"><integer name="maxDepth" value="2"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="toWorld"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sampleCount" value="2"/></sampler>
    <film type="FILM"><integer name="width" value="12"/><integer name="height" value="8"/>PARAMS</film>
  </sensor>
  <emitter type="constant"><spectrum name="radiance" value="1.5"/></emitter>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
</scene>
)";

std::string sceneWith(const std::string &film, const std::string &params) {
    std::string xml = kScene;
    xml.replace(xml.find("FILM"), 4, film);
    xml.replace(xml.find("PARAMS"), 6, params);
    return xml;
}

TEST(RenderOutputs, FilmOptionsReachTheFiles) {
    const std::string cli = cliPath(), dir = tempDir("image-formats-cli");
    ASSERT_FALSE(cli.empty()) << "PATHFARM_CLI is not set (run through ctest)";
    // hdrfilm: a half luminance EXR; the PNG beside it stays the sRGB preview.
    const std::string hdr =
        writeFile(dir, "hdr.xml", sceneWith("hdrfilm", R"(<string name="pixelFormat" value="luminance"/>
        <string name="componentFormat" value="float16"/>)"));
    auto r = runCommand(cli + " render " + hdr + " -q --seed 3 -o " + dir + "/hdr.exr");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const auto channels = channelsOf(dir + "/hdr.exr");
    ASSERT_EQ(channels.size(), 1u);
    EXPECT_EQ(channels[0].first, "Y");
    EXPECT_EQ(channels[0].second, Imf::HALF);
    // ldrfilm with Reinhard's operator and a luminance PNG: the PNG is the tone-mapped EXR beside it.
    const std::string ldr =
        writeFile(dir, "ldr.xml", sceneWith("ldrfilm", R"(<string name="tonemapMethod" value="reinhard"/>
        <float name="key" value="0.3"/><float name="burn" value="0.2"/><float name="gamma" value="2.2"/>
        <string name="pixelFormat" value="luminance"/>)"));
    r = runCommand(cli + " render " + ldr + " -q --seed 3 -o " + dir + "/ldr.exr");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const Bitmap linear = readEXR(dir + "/ldr.exr");
    EXPECT_EQ(pngChannels(dir + "/ldr.png"), 1);
    Bitmap grey(linear.width, linear.height);
    for (int y = 0; y < grey.height; ++y)
        for (int x = 0; x < grey.width; ++x) grey.set(x, y, Spectrum(linear.get(x, y).luminance()));
    ToneMap t;
    t.method = ToneMap::Method::Reinhard;
    t.key = 0.3;
    t.burn = 0.2;
    t.gamma = 2.2;
    const std::vector<double> display = toneMap(grey, t);
    const std::vector<int> codes = pngCodes(dir + "/ldr.png");
    for (size_t i = 0; i < codes.size(); ++i) EXPECT_EQ(codes[i], code(display[i])) << i;
}

// ---- Radiance RGBE, BMP and Targa textures and maps ----

std::shared_ptr<Object> makePlugin(ObjectKind kind, const std::string &type, const std::string &dir,
                                   const std::string &file, const std::string &filter = "") {
    Properties p(kind, type, SourceLocation{"scene.xml", 9});
    p.set("filename", Properties::Type::String, file, {"scene.xml", 10});
    if (!filter.empty()) p.set("filterType", Properties::Type::String, filter, {"scene.xml", 11});
    const PluginFactory *f = findPlugin(kind, type);
    return (*f)(p, LoadContext{dir, dir});
}

Spectrum texel(const Texture &t, int x, int y, int w, int h) {
    Intersection its;
    its.uv = Vec2((x + 0.5) / w, (y + 0.5) / h);
    return t.eval(its);
}

TEST(TextureFormats, RadianceBmpAndTargaTexturesReadBack) {
    const std::string dir = tempDir("image-formats-textures");
    constexpr int w = 4, h = 3;
    std::vector<float> radiance;
    std::vector<unsigned char> bytes;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < 3; ++k) {
                radiance.push_back(static_cast<float>(0.25 * (x + 1) * (k + 1) + 8.0 * y));  // up to 19
                bytes.push_back(static_cast<unsigned char>(20 * x + 60 * y + 7 * k));
            }
    ASSERT_TRUE(stbi_write_hdr((dir + "/t.hdr").c_str(), w, h, 3, radiance.data()));
    ASSERT_TRUE(stbi_write_bmp((dir + "/t.bmp").c_str(), w, h, 3, bytes.data()));
    stbi_write_tga_with_rle = 0;
    ASSERT_TRUE(stbi_write_tga((dir + "/t.tga").c_str(), w, h, 3, bytes.data()));
    stbi_write_tga_with_rle = 1;
    ASSERT_TRUE(stbi_write_tga((dir + "/rle.tga").c_str(), w, h, 3, bytes.data()));

    // Radiance RGBE: linear, shared 8-bit exponent (relative error below 2^-8 of the largest channel).
    const auto hdr =
        std::dynamic_pointer_cast<Texture>(makePlugin(ObjectKind::Texture, "bitmap", dir, "t.hdr", "nearest"));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int k = 0; k < 3; ++k) {
                const double v = radiance[static_cast<size_t>((y * w + x) * 3 + k)], m = 0.25 * (x + 1) * 3 + 8.0 * y;
                EXPECT_NEAR(texel(*hdr, x, y, w, h)[k], v, m / 128) << x << "," << y << "," << k;
            }
    // BMP and Targa: 8-bit sRGB, decoded like PNG.
    for (const char *file : {"t.bmp", "t.tga", "rle.tga"}) {
        const auto t =
            std::dynamic_pointer_cast<Texture>(makePlugin(ObjectKind::Texture, "bitmap", dir, file, "nearest"));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int k = 0; k < 3; ++k)
                    EXPECT_FLOAT_EQ(
                        texel(*t, x, y, w, h)[k],
                        static_cast<float>(srgbToLinear(bytes[static_cast<size_t>((y * w + x) * 3 + k)] / 255.0)))
                        << file << " " << x << "," << y << "," << k;
    }
    // The same through readImage, as envmap loads its map: RGBE stays linear.
    const Bitmap map = readImage(dir + "/t.hdr", true);
    EXPECT_NEAR(map.get(3, 2).b, radiance.back(), radiance.back() / 128);
    const auto env = std::dynamic_pointer_cast<Emitter>(makePlugin(ObjectKind::Emitter, "envmap", dir, "t.hdr"));
    ASSERT_TRUE(env);
}

TEST(TextureFormats, DamagedFilesNameTheFile) {
    const std::string dir = tempDir("image-formats-damaged");
    std::vector<float> radiance(4 * 4 * 3, 1.5f);
    ASSERT_TRUE(stbi_write_hdr((dir + "/good.hdr").c_str(), 4, 4, 3, radiance.data()));
    std::ifstream in(dir + "/good.hdr", std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    writeFile(dir, "truncated.hdr", data.substr(0, data.find("\n\n") + 2 + 8));  // header, size line cut
    writeFile(dir, "short.hdr", data.substr(0, data.size() - 5));                // flat pixels (4 wide), cut
    writeFile(dir, "header.hdr", "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 999999 +X 999999\n");
    writeFile(dir, "garbage.tga", std::string(10, '\x07'));
    writeFile(dir, "notype.tga", std::string("\0\0\x09", 3) + std::string(40, '\0'));
    writeFile(dir, "short.bmp", "BM\x10\0\0\0");
    writeFile(dir, "text.hdr", "just text");
    for (const char *f :
         {"truncated.hdr", "short.hdr", "header.hdr", "garbage.tga", "notype.tga", "short.bmp", "text.hdr"})
        EXPECT_NE(sceneErrorOf([&] { makePlugin(ObjectKind::Texture, "bitmap", dir, f); }).find(f), std::string::npos)
            << f;
}

}  // namespace
}  // namespace pf::test
