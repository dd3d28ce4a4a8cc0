// Image I/O (EXR, PNG, JPEG), reconstruction filters, ImageBlock accumulation and merging, film
// development and the hdrfilm/ldrfilm/rfilter plugin parameters.
#include <gtest/gtest.h>
#include <stb_image_write.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

#include "core/rng.h"
#include "image/bitmap.h"
#include "image/film.h"
#include "scene/plugins.h"

namespace pf {
namespace {

namespace fs = std::filesystem;

// A scratch directory per test, removed afterwards.
class TempDir {
public:
    TempDir() {
        const auto *info = ::testing::UnitTest::GetInstance()->current_test_info();
        path_ = fs::temp_directory_path() / ("pathfarm_test_image_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(path_);
        fs::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path_, ec);
    }
    std::string file(const std::string &name) const { return (path_ / name).string(); }

private:
    fs::path path_;
};

std::vector<char> readBytes(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string &path, const std::vector<char> &bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Expects `fn` to throw a SceneError whose message contains `needle` (a file or parameter name).
void expectSceneError(const std::function<void()> &fn, const std::string &needle) {
    try {
        fn();
        ADD_FAILURE() << "no SceneError; expected one mentioning " << needle;
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
}

Bitmap noiseImage(int w, int h, uint64_t seed) {
    Bitmap img(w, h);
    PCG32 rng(seed, 7);
    for (float &v : img.rgb) v = static_cast<float>(rng.nextDouble());
    return img;
}

// ---- EXR ----

TEST(ImageIO, ExrRoundTripIsExactAndKeepsMetadata) {
    TempDir dir;
    Bitmap img(7, 5);
    PCG32 rng(3, 1);
    for (size_t i = 0; i < img.rgb.size(); ++i) {
        // Values spanning many binades, including ones that half floats could not hold.
        const double mag = std::exp2(rng.nextDouble() * 60.0 - 30.0);
        img.rgb[i] = static_cast<float>(i % 5 == 0 ? 0.0 : mag * (1.0 + rng.nextDouble()));
    }
    img.metadata["pathfarm.spp"] = "1024";
    img.metadata["pathfarm.scene"] = "scenes/cornell box/scene.xml";
    const std::string path = dir.file("round.exr");
    writeEXR(path, img);
    EXPECT_FALSE(fs::exists(path + ".partial"));

    const Bitmap back = readEXR(path);
    ASSERT_EQ(back.width, 7);
    ASSERT_EQ(back.height, 5);
    ASSERT_EQ(back.rgb.size(), img.rgb.size());
    EXPECT_EQ(std::memcmp(back.rgb.data(), img.rgb.data(), img.rgb.size() * sizeof(float)), 0);
    EXPECT_EQ(back.metadata.at("pathfarm.spp"), "1024");
    EXPECT_EQ(back.metadata.at("pathfarm.scene"), "scenes/cornell box/scene.xml");

    const Bitmap viaDispatch = readImage(path, true);  // srgb flag must not touch EXR data
    EXPECT_EQ(std::memcmp(viaDispatch.rgb.data(), img.rgb.data(), img.rgb.size() * sizeof(float)), 0);
}

TEST(ImageIO, BadExrFilesNameTheFile) {
    TempDir dir;
    const std::string good = dir.file("good.exr");
    writeEXR(good, noiseImage(64, 48, 11));
    const std::vector<char> bytes = readBytes(good);
    ASSERT_GT(bytes.size(), 1000u);

    expectSceneError([&] { readEXR(dir.file("missing.exr")); }, "missing.exr");
    const std::string garbage = dir.file("garbage.exr");
    std::vector<char> junk(600);
    PCG32 rng(5, 5);
    for (char &c : junk) c = static_cast<char>(rng.nextUInt(256));
    writeBytes(garbage, junk);
    expectSceneError([&] { readEXR(garbage); }, "garbage.exr");
    // Valid magic number followed by garbage.
    junk[0] = 0x76, junk[1] = 0x2f, junk[2] = 0x31, junk[3] = 0x01;
    writeBytes(garbage, junk);
    expectSceneError([&] { readEXR(garbage); }, "garbage.exr");
    expectSceneError([&] { readImage(garbage, false); }, "garbage.exr");
    for (double frac : {0.1, 0.5, 0.9}) {
        const std::string cut = dir.file("cut.exr");
        writeBytes(cut, std::vector<char>(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() * frac)));
        expectSceneError([&] { readEXR(cut); }, "cut.exr");
    }
}

TEST(ImageIO, WriteRejectsEmptyImageAndBadDirectory) {
    TempDir dir;
    expectSceneError([&] { writeEXR(dir.file("empty.exr"), Bitmap()); }, "empty.exr");
    expectSceneError([&] { writePNG(dir.file("empty.png"), Bitmap()); }, "empty.png");
    const std::string nowhere = dir.file("no/such/dir/out.exr");
    expectSceneError([&] { writeEXR(nowhere, noiseImage(2, 2, 1)); }, "out.exr");
}

// ---- PNG / JPEG ----

TEST(ImageIO, PngTonemapsToSrgbBytes) {
    TempDir dir;
    Bitmap img(6, 1);
    img.set(0, 0, Spectrum(0.5, 0.0, 1.0));           // sRGB(0.5) = 0.7354 -> 188
    img.set(1, 0, Spectrum(2.0, -1.0, NAN));          // clamps; negative and NaN become black
    img.set(2, 0, Spectrum(0.002, 0.0031308, 0.18));  // linear segment: 12.92 * 0.002 * 255 = 6.59 -> 7
    img.set(3, 0, Spectrum(0.25, 0.125, 0.0625));
    img.set(4, 0, Spectrum(1.0, 0.999, 0.001));
    img.set(5, 0, Spectrum(0.214, 0.5, 0.8));
    const std::string path = dir.file("tone.png");
    writePNG(path, img);
    const Bitmap raw = readLDR(path, false);
    ASSERT_EQ(raw.width, 6);
    ASSERT_EQ(raw.height, 1);
    auto byte = [&](int x, int c) { return static_cast<int>(std::lround(raw.get(x, 0)[c] * 255.0)); };
    EXPECT_EQ(byte(0, 0), 188);
    EXPECT_EQ(byte(0, 1), 0);
    EXPECT_EQ(byte(0, 2), 255);
    EXPECT_EQ(byte(1, 0), 255);
    EXPECT_EQ(byte(1, 1), 0);
    EXPECT_EQ(byte(1, 2), 0);
    EXPECT_EQ(byte(2, 0), 7);
    for (int x = 0; x < 6; ++x)
        for (int c = 0; c < 3; ++c) {
            const double v = img.get(x, 0)[c];
            const double expect = std::isnan(v) ? 0.0 : std::round(clamp(linearToSrgb(std::max(v, 0.0)), 0, 1) * 255);
            EXPECT_EQ(byte(x, c), static_cast<int>(expect)) << x << "," << c;
        }

    // One stop of exposure doubles the linear value: 0.25 then encodes like 0.5.
    writePNG(path, img, 1.0);
    EXPECT_EQ(static_cast<int>(std::lround(readLDR(path, false).get(3, 0).r * 255)), 188);
    // A pure power curve (ldrfilm gamma = 2.2): 0.5^(1/2.2) * 255 = 186.1.
    writePNG(path, img, 0.0, 2.2);
    EXPECT_EQ(static_cast<int>(std::lround(readLDR(path, false).get(0, 0).r * 255)), 186);

    // Reading with sRGB decoding inverts the curve up to 8-bit quantisation.
    writePNG(path, img);
    const Bitmap lin = readLDR(path, true);
    EXPECT_NEAR(lin.get(0, 0).r, 0.5, 0.003);
    EXPECT_NEAR(lin.get(3, 0).g, 0.125, 0.002);
    EXPECT_FLOAT_EQ(lin.get(0, 0).r, static_cast<float>(srgbToLinear(188 / 255.0)));
}

TEST(ImageIO, LdrReaderDecodesSrgbAndSixteenBit) {
    TempDir dir;
    // A 2x1 RGB image written byte-exactly with stb.
    const unsigned char px[6] = {0, 128, 255, 10, 200, 64};
    const std::string path = dir.file("bytes.png");
    ASSERT_TRUE(stbi_write_png(path.c_str(), 2, 1, 3, px, 6));
    const Bitmap raw = readLDR(path, false), lin = readLDR(path, true);
    for (int i = 0; i < 6; ++i) {
        EXPECT_FLOAT_EQ(raw.rgb[i], static_cast<float>(px[i] / 255.0));
        EXPECT_FLOAT_EQ(lin.rgb[i], static_cast<float>(srgbToLinear(px[i] / 255.0)));
    }
    // JPEG is lossy; a flat grey image survives closely enough to check the decode path.
    std::vector<unsigned char> grey(16 * 16 * 3, 128);
    const std::string jpg = dir.file("grey.jpg");
    ASSERT_TRUE(stbi_write_jpg(jpg.c_str(), 16, 16, 3, grey.data(), 95));
    const Bitmap j = readImage(jpg, true);
    EXPECT_EQ(j.width, 16);
    EXPECT_NEAR(j.get(5, 5).g, srgbToLinear(128 / 255.0), 0.01);
}

TEST(ImageIO, BadPngAndJpegFilesNameTheFile) {
    TempDir dir;
    const Bitmap noise = noiseImage(64, 64, 9);
    const std::string png = dir.file("good.png");
    writePNG(png, noise);
    std::vector<unsigned char> bytes8(noise.rgb.size());
    for (size_t i = 0; i < bytes8.size(); ++i) bytes8[i] = static_cast<unsigned char>(noise.rgb[i] * 255);
    const std::string jpg = dir.file("good.jpg");
    ASSERT_TRUE(stbi_write_jpg(jpg.c_str(), 64, 64, 3, bytes8.data(), 90));
    ASSERT_NO_THROW(readLDR(jpg, true));
    // Bytes after the end-of-image marker (some cameras append data) do not make a JPEG invalid.
    std::vector<char> trailing = readBytes(jpg);
    trailing.insert(trailing.end(), {0, 0, 'x', 'y', 'z'});
    const std::string withTrailer = dir.file("trailer.jpg");
    writeBytes(withTrailer, trailing);
    EXPECT_EQ(readLDR(withTrailer, false).rgb, readLDR(jpg, false).rgb);

    expectSceneError([&] { readLDR(dir.file("missing.png"), true); }, "missing.png");
    expectSceneError([&] { readImage(dir.file("missing.jpg"), true); }, "missing.jpg");
    fs::create_directories(dir.file("folder.png"));
    expectSceneError([&] { readImage(dir.file("folder.png"), true); }, "folder.png");
    for (const std::string &src : {png, jpg}) {
        const std::vector<char> bytes = readBytes(src);
        const std::string ext = fs::path(src).extension().string();
        // Right magic number, garbage after it.
        std::vector<char> corrupt(bytes.begin(), bytes.begin() + 16);
        PCG32 rng(17, 3);
        for (int i = 0; i < 500; ++i) corrupt.push_back(static_cast<char>(rng.nextUInt(256)));
        const std::string bad = dir.file("corrupt" + ext);
        writeBytes(bad, corrupt);
        expectSceneError([&] { readLDR(bad, true); }, "corrupt" + ext);
        for (double frac : {0.05, 0.3, 0.6, 0.9}) {
            const std::string cut = dir.file("cut" + ext);
            writeBytes(cut, std::vector<char>(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() * frac)));
            expectSceneError([&] { readImage(cut, true); }, "cut" + ext);
        }
    }
    const std::string empty = dir.file("empty.png");
    writeBytes(empty, {});
    expectSceneError([&] { readLDR(empty, true); }, "empty.png");
    const std::string text = dir.file("text.png");
    writeBytes(text, {'h', 'e', 'l', 'l', 'o'});
    expectSceneError([&] { readLDR(text, true); }, "text.png");
}

// A well-formed Huffman table segment holding 300 codes: stb_image 2.27 would write past its tables.
TEST(ImageIO, OversizedJpegHuffmanTableIsRejected) {
    TempDir dir;
    std::vector<unsigned char> grey(8 * 8 * 3, 90);
    const std::string jpg = dir.file("dht.jpg");
    ASSERT_TRUE(stbi_write_jpg(jpg.c_str(), 8, 8, 3, grey.data(), 90));
    const std::vector<char> bytes = readBytes(jpg);
    // An extra DHT segment right after the start-of-image marker, for AC table 3 (unused by the
    // scans): marker, length, class/id, 16 code counts summing to 300, then the 300 code values.
    const int codes = 300, length = 2 + 17 + codes;
    std::vector<char> segment = {'\xff', '\xc4', static_cast<char>(length >> 8), static_cast<char>(length & 0xff),
                                 0x13};
    for (int i = 1; i <= 16; ++i) segment.push_back(static_cast<char>(i == 15 ? 45 : (i == 16 ? 255 : 0)));
    for (int i = 0; i < codes; ++i) segment.push_back(static_cast<char>(i & 0xff));
    std::vector<char> damaged;
    damaged.reserve(bytes.size() + segment.size());
    for (const auto &part : {std::vector<char>(bytes.begin(), bytes.begin() + 2), segment,
                             std::vector<char>(bytes.begin() + 2, bytes.end())})
        damaged.insert(damaged.end(), part.begin(), part.end());
    const std::string bad = dir.file("bad_dht.jpg");
    writeBytes(bad, damaged);
    expectSceneError([&] { readLDR(bad, true); }, "bad_dht.jpg");
    try {
        readLDR(bad, true);
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find("more than 256 codes"), std::string::npos) << e.what();
    }
}

// Randomly damaged files (bytes overwritten, tails cut off) either decode or raise a SceneError; any
// other outcome (another exception, a crash, a hang) fails. The ASan/UBSan build runs this too.
TEST(ImageIO, RandomlyDamagedFilesNeverEscapeAsOtherErrors) {
    TempDir dir;
    const Bitmap noise = noiseImage(29, 17, 4);
    writeEXR(dir.file("src.exr"), noise);
    writePNG(dir.file("src.png"), noise);
    std::vector<unsigned char> bytes8(noise.rgb.size());
    for (size_t i = 0; i < bytes8.size(); ++i) bytes8[i] = static_cast<unsigned char>(noise.rgb[i] * 255);
    ASSERT_TRUE(stbi_write_jpg(dir.file("src.jpg").c_str(), 29, 17, 3, bytes8.data(), 85));
    PCG32 rng(2024, 9);
    for (const std::string ext : {".exr", ".png", ".jpg"}) {
        const std::vector<char> original = readBytes(dir.file("src" + ext));
        int decoded = 0, rejected = 0;
        for (int it = 0; it < 150; ++it) {
            std::vector<char> damaged = original;
            const int writes = 1 + static_cast<int>(rng.nextUInt(6));
            for (int k = 0; k < writes; ++k)
                damaged[rng.nextUInt(static_cast<uint32_t>(damaged.size()))] = static_cast<char>(rng.nextUInt(256));
            if (rng.nextUInt(3) == 0) damaged.resize(rng.nextUInt(static_cast<uint32_t>(damaged.size())));
            const std::string path = dir.file("damaged" + ext);
            writeBytes(path, damaged);
            try {
                const Bitmap img = readImage(path, true);
                EXPECT_EQ(img.rgb.size(), static_cast<size_t>(img.width) * img.height * 3);
                ++decoded;
            } catch (const SceneError &e) {
                EXPECT_NE(std::string(e.what()).find("damaged" + ext), std::string::npos) << e.what();
                ++rejected;
            }
        }
        // Both outcomes occur, so the loop exercises the decoders and the error paths.
        EXPECT_GT(decoded, 0) << ext;
        EXPECT_GT(rejected, 0) << ext;
    }
}

// ---- reconstruction filters ----

double integrate(const ReconstructionFilter &f) {
    // Composite Simpson on [-r, r]; every filter here is smooth enough between its kinks at integers
    // and the ends for 20000 intervals to be exact to ~1e-10 (the box's jumps sit on the ends).
    const int n = 20000;
    const double r = f.radius(), h = 2 * r / n;
    double sum = f.eval(-r) + f.eval(r);
    for (int i = 1; i < n; ++i) sum += f.eval(-r + i * h) * (i % 2 ? 4 : 2);
    return sum * h / 3;
}

TEST(Filters, RadiiAndNormalisation) {
    EXPECT_EQ(BoxFilter().radius(), 0.5);
    EXPECT_EQ(TentFilter().radius(), 1.0);
    EXPECT_EQ(GaussianFilter().radius(), 2.0);
    EXPECT_EQ(BoxFilter().borderSize(), 0);
    EXPECT_EQ(TentFilter().borderSize(), 1);
    EXPECT_EQ(GaussianFilter().borderSize(), 2);
    EXPECT_EQ(LanczosSincFilter(3).borderSize(), 3);

    EXPECT_NEAR(integrate(BoxFilter()), 1.0, 1e-9);
    EXPECT_NEAR(integrate(BoxFilter(1.5)), 3.0, 1e-9);
    EXPECT_NEAR(integrate(TentFilter()), 1.0, 1e-9);
    // Truncated, shifted Gaussian: sigma sqrt(2 pi) erf(r / (sigma sqrt 2)) - 2 r exp(-r^2 / (2 sigma^2)).
    for (double s : {0.5, 0.3, 1.2}) {
        const double r = 4 * s;
        const double expect = s * std::sqrt(2 * kPi) * std::erf(r / (s * std::sqrt(2.0))) - 2 * r * std::exp(-8.0);
        EXPECT_NEAR(integrate(GaussianFilter(s)), expect, 1e-9) << s;
        EXPECT_EQ(GaussianFilter(s).eval(r), 0.0);
    }
    // The Mitchell-Netravali family integrates to one for every (B, C).
    EXPECT_NEAR(integrate(MitchellNetravaliFilter()), 1.0, 1e-9);
    EXPECT_NEAR(integrate(MitchellNetravaliFilter(0.0, 0.5)), 1.0, 1e-9);
    EXPECT_NEAR(MitchellNetravaliFilter(0.0, 0.5).eval(1.0), 0.0, 1e-15);  // Catmull-Rom interpolates
    EXPECT_NEAR(MitchellNetravaliFilter(0.0, 0.5).eval(0.0), 1.0, 1e-15);
    const LanczosSincFilter lanczos(3);
    EXPECT_EQ(lanczos.eval(0.0), 1.0);
    for (int k = 1; k <= 3; ++k) EXPECT_NEAR(lanczos.eval(k), 0.0, 1e-15);
    EXPECT_EQ(lanczos.eval(3.01), 0.0);
}

std::vector<std::shared_ptr<ReconstructionFilter>> allFilters() {
    return {std::make_shared<BoxFilter>(),
            std::make_shared<TentFilter>(),
            std::make_shared<GaussianFilter>(),
            std::make_shared<MitchellNetravaliFilter>(),
            std::make_shared<MitchellNetravaliFilter>(0.0, 0.5),
            std::make_shared<LanczosSincFilter>(3)};
}

TEST(Film, ConstantImageDevelopsToTheConstantWhateverTheFilter) {
    const Spectrum c(0.3, 1.7, 42.0);
    for (const auto &filter : allFilters()) {
        const auto film = Film::create(13, 9, filter);
        ImageBlock block(0, 0, 13, 9, filter.get());
        PCG32 rng(21, 4);
        for (int y = 0; y < 9; ++y)
            for (int x = 0; x < 13; ++x)
                for (int s = 0; s < 16; ++s)  // 4x4 jittered positions per pixel
                    block.put(Vec2(x + (s % 4 + rng.nextDouble()) / 4, y + (s / 4 + rng.nextDouble()) / 4), c);
        const Bitmap img = film->develop(block, 0.0);
        for (int y = 0; y < 9; ++y)
            for (int x = 0; x < 13; ++x)
                for (int k = 0; k < 3; ++k)
                    ASSERT_NEAR(img.get(x, y)[k], static_cast<float>(c[k]), 1e-5 * c[k])
                        << "filter radius " << filter->radius() << " pixel " << x << "," << y;
    }
}

TEST(ImageBlock, PutNearBordersKeepsTheWholeFootprint) {
    const GaussianFilter g;
    ImageBlock block(0, 0, 8, 6, &g);
    EXPECT_EQ(block.border(), 2);
    for (const Vec2 p : {Vec2(0.0, 0.0), Vec2(0.1, 5.99), Vec2(7.999, 0.3), Vec2(3.5, 3.5)}) {
        block.clear();
        block.put(p, Spectrum(2.0));
        // Expected weight: the separable footprint over every pixel centre within the radius.
        double wx = 0, wy = 0;
        for (int i = -10; i < 20; ++i) {
            wx += std::abs(i + 0.5 - p.x) <= g.radius() ? g.eval(i + 0.5 - p.x) : 0.0;
            wy += std::abs(i + 0.5 - p.y) <= g.radius() ? g.eval(i + 0.5 - p.y) : 0.0;
        }
        double total = 0, totalSum = 0;
        for (int y = -2; y < 8; ++y)
            for (int x = -2; x < 10; ++x) {
                total += block.weight(x, y);
                totalSum += block.weightedSum(x, y).g;
            }
        EXPECT_NEAR(total, wx * wy, 1e-12) << p.x << "," << p.y;
        EXPECT_NEAR(totalSum, 2 * wx * wy, 1e-12);
    }
    EXPECT_THROW(block.weight(-3, 0), std::out_of_range);
    EXPECT_THROW(block.weight(10, 0), std::out_of_range);
}

TEST(ImageBlock, InvalidSamplesAreCountedNotStored) {
    const TentFilter t;
    ImageBlock block(0, 0, 4, 4, &t);
    block.put(Vec2(1.5, 1.5), Spectrum(NAN, 0, 0));
    block.put(Vec2(INFINITY, 1.5), Spectrum(1.0));
    block.splat(Vec2(1.5, 1.5), Spectrum(0, INFINITY, 0));
    block.put(Vec2(1e300, -1e300), Spectrum(1.0));  // finite but far away: dropped silently
    EXPECT_EQ(block.invalidSamples(), 3u);
    for (int y = -1; y < 5; ++y)
        for (int x = -1; x < 5; ++x) {
            EXPECT_EQ(block.weight(x, y), 0.0);
            EXPECT_TRUE(block.splatSum(x, y).isBlack());
        }
    ImageBlock total(0, 0, 4, 4, &t);
    total.merge(block);
    total.merge(block);
    EXPECT_EQ(total.invalidSamples(), 6u);
}

TEST(ImageBlock, SplatsAreFilteredKeptApartAndScaledOnDevelop) {
    const auto film = Film::create(4, 3, std::make_shared<TentFilter>());
    ImageBlock block(0, 0, 4, 3, &film->filter());
    block.put(Vec2(1.2, 0.9), Spectrum(1.0, 2.0, 3.0));
    block.splat(Vec2(2.5, 1.5), Spectrum(8.0));  // a pixel centre: only that pixel, with weight 1
    block.splat(Vec2(2.0, 1.5), Spectrum(4.0));  // between pixels 1 and 2: half to each
    EXPECT_EQ(block.splatSum(2, 1).r, 10.0);
    EXPECT_EQ(block.splatSum(1, 1).r, 2.0);
    EXPECT_EQ(block.weight(2, 1), 0.0);  // splats carry no filter weight
    const Bitmap img = film->develop(block, 0.25);
    EXPECT_FLOAT_EQ(img.get(0, 0).g, 2.0f);
    // Pixel (1, 1) is at the film's left and top border only through its filter footprint: the tent's
    // coverage is 1 for interior pixels of a row and 7/8 for the end pixels.
    const std::vector<double> cx = filterCoverage(film->filter(), 4), cy = filterCoverage(film->filter(), 3);
    EXPECT_NEAR(cx[0], 0.875, 1e-12);
    EXPECT_NEAR(cx[1], 1.0, 1e-12);
    EXPECT_NEAR(cy[1], 1.0, 1e-12);
    const Bitmap noSplat = film->develop(block, 0.0);
    EXPECT_NEAR(img.get(2, 1).b - noSplat.get(2, 1).b, 0.25 * 10.0, 1e-6);
    EXPECT_NEAR(img.get(1, 1).r - noSplat.get(1, 1).r, 0.25 * 2.0, 1e-6);
    ImageBlock small(0, 0, 3, 3, &film->filter());
    EXPECT_THROW(film->develop(small, 1.0), std::invalid_argument);
}

TEST(Film, FilterCoverageIsTheFilterIntegralOverTheRow) {
    const BoxFilter box;
    for (double c : filterCoverage(box, 5)) EXPECT_NEAR(c, 1.0, 1e-12);
    // Mitsuba's gaussian (stddev 0.5): exp(-2 x^2) - exp(-8) on [-2, 2].
    const GaussianFilter g;
    const double full = std::sqrt(M_PI / 2) * std::erf(2 * std::sqrt(2.0)) - 4 * std::exp(-8.0);
    const std::vector<double> c = filterCoverage(g, 9);
    EXPECT_NEAR(c[4], full, 1e-9);
    // The end pixel keeps the half of the footprint inside the row, plus the half pixel before its centre.
    const double half = std::sqrt(M_PI / 2) * std::erf(2 * std::sqrt(2.0)) / 2 - 2 * std::exp(-8.0);
    const double inner = std::sqrt(M_PI / 2) * std::erf(std::sqrt(2.0) * 0.5) / 2 - 0.5 * std::exp(-8.0);
    EXPECT_NEAR(c[0], half + inner, 1e-9);
    EXPECT_NEAR(c[8], c[0], 1e-12);
}

// Splats and filtered samples of the same function develop to the same image: the camera image's weighted
// average and the splat image divided by the filter's coverage both converge to int f L / int f, at an edge
// of L and at the border of the film. Stratified deterministic positions stand in for the estimators.
TEST(Film, SplatsAndFilteredSamplesDevelopToTheSameImage) {
    for (const auto &filter : std::vector<std::shared_ptr<ReconstructionFilter>>{
             std::make_shared<TentFilter>(), std::make_shared<GaussianFilter>(),
             std::make_shared<MitchellNetravaliFilter>()}) {
        const int W = 6, H = 5, K = 32;
        const auto film = Film::create(W, H, filter);
        ImageBlock put(0, 0, W, H, &film->filter()), splat(0, 0, W, H, &film->filter());
        const auto L = [](const Vec2 &p) { return p.x < 2.3 ? Spectrum(4.0) : Spectrum(1.0); };
        for (int y = 0; y < H * K; ++y)
            for (int x = 0; x < W * K; ++x) {
                const Vec2 p((x + 0.5) / K, (y + 0.5) / K);
                put.put(p, L(p));
                splat.splat(p, L(p));
            }
        const Bitmap a = film->develop(put, 0.0), b = film->develop(splat, 1.0 / (K * K));
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) EXPECT_NEAR(a.get(x, y).r, b.get(x, y).r, 2e-3) << x << "," << y;
    }
}

TEST(ImageBlock, WithoutFilterSamplesCountForTheirPixel) {
    ImageBlock block(2, 1, 3, 2, nullptr);
    EXPECT_EQ(block.border(), 0);
    block.put(Vec2(2.0, 1.0), Spectrum(1.0));
    block.put(Vec2(2.99, 1.5), Spectrum(3.0));
    block.put(Vec2(1.99, 1.5), Spectrum(5.0));  // outside the block: dropped
    EXPECT_EQ(block.weight(2, 1), 2.0);
    EXPECT_EQ(block.weightedSum(2, 1), Spectrum(4.0));
    EXPECT_EQ(block.weight(3, 1), 0.0);
    EXPECT_THROW(block.weight(1, 1), std::out_of_range);
}

// Renders the same samples into per-tile blocks and into one block, like the render loop does.
TEST(ImageBlock, MergedTilesEqualOneBlock) {
    const GaussianFilter g;
    const int W = 40, H = 24, T = 16;
    ImageBlock whole(0, 0, W, H, &g), merged(0, 0, W, H, &g), mergedAgain(0, 0, W, H, &g);
    std::vector<ImageBlock> tiles;
    for (int ty = 0; ty < H; ty += T)
        for (int tx = 0; tx < W; tx += T) {
            tiles.emplace_back(tx, ty, std::min(T, W - tx), std::min(T, H - ty), &g);
            ImageBlock &tile = tiles.back();
            for (int y = ty; y < ty + tile.height(); ++y)
                for (int x = tx; x < tx + tile.width(); ++x) {
                    PCG32 rng(hashCombine(99, static_cast<uint64_t>(y * W + x)), 1);
                    for (int s = 0; s < 4; ++s) {
                        const Vec2 p(x + rng.nextDouble(), y + rng.nextDouble());
                        const Spectrum v(rng.nextDouble(), 10 * rng.nextDouble(), rng.nextDouble());
                        tile.put(p, v);
                        whole.put(p, v);
                        if (s == 0) {
                            tile.splat(p, v);
                            whole.splat(p, v);
                        }
                    }
                }
        }
    for (const ImageBlock &t : tiles) merged.merge(t);
    for (const ImageBlock &t : tiles) mergedAgain.merge(t);
    const int b = g.borderSize();
    // Samples reaching pixel x lie in pixels x - b .. x + b.
    auto oneTile = [&](int x, int n) { return x - b >= 0 && x + b < n && (x - b) / T == (x + b) / T; };
    int bitwiseChecked = 0;
    for (int y = -b; y < H + b; ++y)
        for (int x = -b; x < W + b; ++x) {
            // Same blocks in the same order: the same bits.
            ASSERT_EQ(merged.weight(x, y), mergedAgain.weight(x, y));
            ASSERT_EQ(merged.weightedSum(x, y), mergedAgain.weightedSum(x, y));
            ASSERT_EQ(merged.splatSum(x, y), mergedAgain.splatSum(x, y));
            // Equal to the single block up to the order of additions ...
            ASSERT_NEAR(merged.weight(x, y), whole.weight(x, y), 1e-12 * (1 + whole.weight(x, y)));
            ASSERT_NEAR(merged.weightedSum(x, y).g, whole.weightedSum(x, y).g, 1e-12 * (1 + whole.weightedSum(x, y).g));
            ASSERT_NEAR(merged.splatSum(x, y).g, whole.splatSum(x, y).g, 1e-12 * (1 + whole.splatSum(x, y).g));
            // ... and bitwise where all samples that reach the pixel come from one tile (the same
            // additions in the same order).
            if (oneTile(x, W) && oneTile(y, H)) {
                ASSERT_EQ(merged.weight(x, y), whole.weight(x, y)) << x << "," << y;
                ASSERT_EQ(merged.weightedSum(x, y), whole.weightedSum(x, y)) << x << "," << y;
                ++bitwiseChecked;
            }
        }
    EXPECT_GT(bitwiseChecked, 200);
    // A tile whose border reaches past the target block is refused, not clipped.
    ImageBlock part(0, 0, 16, 16, &g);
    EXPECT_THROW(part.merge(tiles[1]), std::invalid_argument);
}

// A chain task's film (BlockStorage::Tiles) holds exactly the splat sums of a dense block that received the
// same splats, bit for bit, and merging it adds exactly what merging that dense block adds: filters whose
// footprint crosses tiles (Lanczos with 16 lobes spans 33 pixels, 5 or 6 tiles) and negative lobes, no
// filter, an offset block, splats beyond the border and invalid ones, clustered so that most tiles stay
// unallocated.
TEST(ImageBlock, TilesHoldTheDenseSplatsBitForBit) {
    auto filters = allFilters();
    filters.push_back(std::make_shared<LanczosSincFilter>(16));
    filters.push_back(nullptr);
    const auto sameBits = [](std::span<const double> a, std::span<const double> b) {
        return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
    };
    for (const auto &filter : filters) {
        const int X = 5, Y = 3, W = 400, H = 300;
        ImageBlock dense(X, Y, W, H, filter.get()), tiles(X, Y, W, H, filter.get(), BlockStorage::Tiles);
        PCG32 rng(7, 3);
        for (int i = 0; i < 3000; ++i) {
            // Near one spot but for every 300th, which lands anywhere, outside the block and its border too.
            const bool near = i % 300 != 0;
            const Vec2 p = near ? Vec2(X + 60 + 25 * rng.nextDouble(), Y + 20 + 30 * rng.nextDouble())
                                : Vec2(X - 40 + (W + 80) * rng.nextDouble(), Y - 40 + (H + 80) * rng.nextDouble());
            const Spectrum v = i == 100 ? Spectrum(NAN) : Spectrum(rng.nextDouble(), 1e-9, 1e9 * rng.nextDouble());
            dense.splat(p, v);
            tiles.splat(p, v);
        }
        const std::string name = filter ? "filter radius " + std::to_string(filter->radius()) : "no filter";
        EXPECT_EQ(tiles.invalidSamples(), 1u) << name;
        EXPECT_TRUE(tiles.sumData().empty() && tiles.weightData().empty() && tiles.splatData().empty());
        ASSERT_NE(tiles.tiles(), nullptr);
        EXPECT_EQ(dense.tiles(), nullptr);
        // Most of the (W + 2b) x (H + 2b) storage was never touched, so most tiles are not allocated.
        EXPECT_LT(tiles.storedValues(), dense.splatData().size() / 2) << name;
        EXPECT_GT(tiles.storedValues(), 0u);
        const int b = dense.border();
        for (int y = Y - b; y < Y + H + b; ++y)
            for (int x = X - b; x < X + W + b; ++x) {
                const Spectrum d = dense.splatSum(x, y), t = tiles.splatSum(x, y);
                ASSERT_EQ(std::memcmp(&d, &t, sizeof d), 0) << name << " pixel " << x << "," << y;
                ASSERT_EQ(tiles.weight(x, y), 0.0);
                ASSERT_TRUE(tiles.weightedSum(x, y).isBlack());
            }
        EXPECT_THROW(tiles.splatSum(X - b - 1, Y), std::out_of_range);

        // Merged twice into films that already hold deposits, as a task's result joins the chains' film.
        ImageBlock viaDense(0, 0, X + W, Y + H, filter.get()), viaTiles(0, 0, X + W, Y + H, filter.get());
        for (ImageBlock *f : {&viaDense, &viaTiles}) f->splat(Vec2(X + 70.2, Y + 30.7), Spectrum(3.0));
        for (int k = 0; k < 2; ++k) {
            viaDense.merge(dense);
            viaTiles.merge(tiles);
        }
        EXPECT_TRUE(sameBits(viaDense.splatData(), viaTiles.splatData())) << name;
        EXPECT_TRUE(sameBits(viaDense.sumData(), viaTiles.sumData()));
        EXPECT_TRUE(sameBits(viaDense.weightData(), viaTiles.weightData()));
        EXPECT_EQ(viaTiles.invalidSamples(), 2u);

        EXPECT_THROW(tiles.put(Vec2(X + 1.0, Y + 1.0), Spectrum(1.0)), std::logic_error);
        EXPECT_THROW(tiles.merge(dense), std::logic_error);
        tiles.clear();
        EXPECT_EQ(tiles.storedValues(), 0u);
        EXPECT_EQ(tiles.invalidSamples(), 0u);
        EXPECT_TRUE(tiles.splatSum(X + 70, Y + 30).isBlack());
    }
}

// ---- film and rfilter plugins ----

// Straight from this area's plugin tables, so that these tests do not depend on the other plugin areas.
PluginFactory factory(ObjectKind kind, const std::string &type) {
    for (const auto &[name, f] : kind == ObjectKind::Film ? filmPlugins() : rfilterPlugins())
        if (name == type) return f;
    throw std::runtime_error("no plugin " + type);
}

struct PluginParams {
    Properties props;
    PluginParams(ObjectKind kind, const std::string &type) : props(kind, type, SourceLocation{"scene.xml", 10}) {}
    PluginParams &integer(const std::string &n, int64_t v) {
        props.set(n, Properties::Type::Integer, v, {"scene.xml", 11});
        return *this;
    }
    PluginParams &real(const std::string &n, double v) {
        props.set(n, Properties::Type::Float, v, {"scene.xml", 12});
        return *this;
    }
    PluginParams &string(const std::string &n, const std::string &v) {
        props.set(n, Properties::Type::String, v, {"scene.xml", 13});
        return *this;
    }
    PluginParams &boolean(const std::string &n, bool v) {
        props.set(n, Properties::Type::Boolean, v, {"scene.xml", 14});
        return *this;
    }
    PluginParams &child(ObjectKind kind, std::shared_ptr<Object> obj) {
        props.addChild({"", kind, std::move(obj), {"scene.xml", 15}});
        return *this;
    }
    std::shared_ptr<Object> build(const std::string &type) const {
        auto obj = factory(props.kind(), type)(props, LoadContext{".", "."});
        props.checkAllUsed();
        return obj;
    }
};

std::shared_ptr<Film> makeFilm(const PluginParams &p) {
    return std::dynamic_pointer_cast<Film>(p.build(p.props.pluginName()));
}

TEST(FilmPlugins, MitsubaDefaults) {
    const auto hdr = makeFilm(PluginParams(ObjectKind::Film, "hdrfilm"));
    ASSERT_TRUE(hdr);
    EXPECT_EQ(hdr->width(), 768);
    EXPECT_EQ(hdr->height(), 576);
    EXPECT_EQ(hdr->cropX(), 0);
    EXPECT_EQ(hdr->cropWidth(), 768);
    EXPECT_EQ(hdr->cropHeight(), 576);
    EXPECT_TRUE(hdr->isHDR());
    EXPECT_EQ(hdr->fileFormat(), "openexr");
    EXPECT_FALSE(hdr->highQualityEdges());
    const auto *gauss = dynamic_cast<const GaussianFilter *>(&hdr->filter());
    ASSERT_NE(gauss, nullptr);
    EXPECT_EQ(gauss->stddev(), 0.5);

    // The film of the bundled Cornell box scene.
    const auto ldr = makeFilm(PluginParams(ObjectKind::Film, "ldrfilm")
                                  .integer("width", 1024)
                                  .integer("height", 1024)
                                  .string("fileFormat", "png")
                                  .string("pixelFormat", "rgb")
                                  .real("gamma", 2.2)
                                  .boolean("banner", false)
                                  .child(ObjectKind::RFilter, std::make_shared<TentFilter>()));
    ASSERT_TRUE(ldr);
    EXPECT_FALSE(ldr->isHDR());
    EXPECT_EQ(ldr->gamma(), 2.2);
    EXPECT_EQ(ldr->exposure(), 0.0);
    EXPECT_EQ(ldr->fileFormat(), "png");
    EXPECT_EQ(ldr->filter().radius(), 1.0);

    const auto cropped = makeFilm(PluginParams(ObjectKind::Film, "hdrfilm")
                                      .integer("width", 100)
                                      .integer("height", 50)
                                      .integer("cropOffsetX", 10)
                                      .integer("cropOffsetY", 5)
                                      .integer("cropWidth", 90)
                                      .integer("cropHeight", 20)
                                      .string("pixelFormat", "RGBA")
                                      .string("componentFormat", "float32")
                                      .boolean("highQualityEdges", true)
                                      .boolean("attachLog", false));
    EXPECT_EQ(cropped->cropX(), 10);
    EXPECT_EQ(cropped->cropY(), 5);
    EXPECT_EQ(cropped->cropWidth(), 90);
    EXPECT_EQ(cropped->cropHeight(), 20);
    EXPECT_TRUE(cropped->highQualityEdges());
    const auto jpeg = makeFilm(PluginParams(ObjectKind::Film, "ldrfilm")
                                   .string("fileFormat", "jpg")
                                   .real("exposure", -1.5)
                                   .string("tonemapMethod", "reinhard")
                                   .real("key", 0.25)
                                   .real("burn", 0.5));
    EXPECT_EQ(jpeg->fileFormat(), "jpeg");
    EXPECT_EQ(jpeg->exposure(), -1.5);
}

TEST(FilmPlugins, BadParametersNameTheParameter) {
    using P = PluginParams;
    const auto F = ObjectKind::Film;
    auto fails = [](const P &p, const std::string &param) {
        expectSceneError([&] { makeFilm(p); }, "'" + param + "'");
    };
    fails(P(F, "hdrfilm").integer("width", 0), "width");
    fails(P(F, "hdrfilm").integer("width", -5), "width");
    fails(P(F, "hdrfilm").integer("width", 32769), "width");
    fails(P(F, "hdrfilm").integer("height", 1000000000000LL), "height");
    fails(P(F, "hdrfilm").integer("width", 30000).integer("height", 30000), "height");
    fails(P(F, "hdrfilm").integer("cropOffsetX", 768), "cropOffsetX");
    fails(P(F, "hdrfilm").integer("cropOffsetY", -1), "cropOffsetY");
    fails(P(F, "hdrfilm").integer("cropOffsetX", 100).integer("cropWidth", 700), "cropWidth");
    fails(P(F, "hdrfilm").integer("cropHeight", 0), "cropHeight");
    fails(P(F, "hdrfilm").integer("cropOffsetX", 100), "cropWidth");  // default crop width is the film's
    fails(P(F, "hdrfilm").string("pixelFormat", "spectrum"), "pixelFormat");
    fails(P(F, "hdrfilm").string("pixelFormat", "rgb, rgba"), "pixelFormat");
    fails(P(F, "hdrfilm").string("componentFormat", "float64"), "componentFormat");
    fails(P(F, "hdrfilm").string("fileFormat", "png"), "fileFormat");
    fails(P(F, "ldrfilm").string("fileFormat", "openexr"), "fileFormat");
    fails(P(F, "ldrfilm").real("gamma", 0.0), "gamma");
    fails(P(F, "ldrfilm").real("exposure", 1e6), "exposure");
    fails(P(F, "ldrfilm").string("tonemapMethod", "aces"), "tonemapMethod");
    fails(P(F, "ldrfilm").real("burn", 2.0), "burn");
    fails(P(F, "ldrfilm").real("key", 0.0), "key");
    fails(P(F, "hdrfilm").boolean("banner", true).integer("width", 10).real("gamma", 2.2),
          "gamma");  // hdrfilm has none
    expectSceneError([&] { makeFilm(P(F, "hdrfilm").string("width", "wide")); }, "width");
    expectSceneError(
        [&] {
            makeFilm(P(F, "hdrfilm")
                         .child(ObjectKind::RFilter, std::make_shared<BoxFilter>())
                         .child(ObjectKind::RFilter, std::make_shared<TentFilter>()));
        },
        "rfilter");

    auto filterFails = [](const P &p, const std::string &type, const std::string &param) {
        expectSceneError([&] { p.build(type); }, "'" + param + "'");
    };
    const auto R = ObjectKind::RFilter;
    filterFails(P(R, "gaussian").real("stddev", 0.0), "gaussian", "stddev");
    filterFails(P(R, "gaussian").real("stddev", 5.0), "gaussian", "stddev");
    filterFails(P(R, "box").real("radius", -1.0), "box", "radius");
    filterFails(P(R, "lanczos").integer("lobes", 0), "lanczos", "lobes");
    filterFails(P(R, "tent").real("radius", 2.0), "tent", "radius");  // Mitsuba's tent has no radius

    EXPECT_THROW(Film::create(0, 10, nullptr), SceneError);
    EXPECT_THROW(Film::create(40000, 10, nullptr), SceneError);
    EXPECT_THROW(Film::create(20000, 20000, nullptr), SceneError);
}

TEST(FilmPlugins, FilterParameters) {
    using P = PluginParams;
    const auto R = ObjectKind::RFilter;
    auto radius = [](const std::shared_ptr<Object> &o) {
        return std::dynamic_pointer_cast<ReconstructionFilter>(o)->radius();
    };
    EXPECT_EQ(radius(P(R, "box").build("box")), 0.5);
    EXPECT_EQ(radius(P(R, "box").real("radius", 1.5).build("box")), 1.5);
    EXPECT_EQ(radius(P(R, "tent").build("tent")), 1.0);
    EXPECT_EQ(radius(P(R, "gaussian").build("gaussian")), 2.0);
    EXPECT_EQ(radius(P(R, "gaussian").real("stddev", 0.25).build("gaussian")), 1.0);
    EXPECT_EQ(radius(P(R, "mitchell").real("B", 0.5).real("C", 0.25).build("mitchell")), 2.0);
    EXPECT_EQ(radius(P(R, "catmullrom").build("catmullrom")), 2.0);
    EXPECT_EQ(radius(P(R, "lanczos").integer("lobes", 2).build("lanczos")), 2.0);
    const auto f = Film::create(8, 4, nullptr);
    EXPECT_NE(dynamic_cast<const GaussianFilter *>(&f->filter()), nullptr);
}

}  // namespace
}  // namespace pf
