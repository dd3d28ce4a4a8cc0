// The farm's wire layer in-process: film blocks survive encoding bit for bit and corrupt ones are
// refused; bundles collect what a scene references, refuse entries that leave the bundle, and are only
// stored when every byte matches the manifest.
#include <gtest/gtest.h>
#include <zstd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <random>

#include "farm/block_codec.h"
#include "farm/bundle.h"
#include "farm/chain_codec.h"
#include "farm/error.h"
#include "farm/harness.h"
#include "farm/hash.h"
#include "farm/rpc.h"
#include "image/rfilter.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace fs = std::filesystem;
using pf::farm::FarmError;

ImageBlock randomBlock(const ReconstructionFilter &filter, uint32_t seed) {
    ImageBlock b(0, 0, 37, 23, &filter);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 2000; ++i) {
        const Vec2 p(u(rng) * 37, u(rng) * 23);
        b.put(p, Spectrum(u(rng), u(rng) * 1e-7, u(rng) * 1e9));
        if (i % 3 == 0) b.splat(p, Spectrum(u(rng), 0, 1));
    }
    b.put(Vec2(1, 1), Spectrum(std::nan(""), 0, 0));  // counted as invalid, which must travel too
    return b;
}

bool sameStorage(const ImageBlock &a, const ImageBlock &b) {
    auto same = [](std::span<const double> x, std::span<const double> y) {
        return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0;
    };
    return same(a.sumData(), b.sumData()) && same(a.weightData(), b.weightData()) &&
           same(a.splatData(), b.splatData()) && a.invalidSamples() == b.invalidSamples();
}

TEST(FarmWire, BlocksRoundTripBitForBit) {
    const GaussianFilter filter;
    const ImageBlock original = randomBlock(filter, 1);
    const std::string data = pf::farm::encodeBlock(original);
    ImageBlock decoded(0, 0, 37, 23, &filter);
    pf::farm::decodeBlock(data, decoded);
    EXPECT_TRUE(sameStorage(original, decoded));
    EXPECT_EQ(decoded.invalidSamples(), 1u);
    // Byte shuffling is what makes doubles compressible at all.
    EXPECT_LT(data.size(), 7 * sizeof(double) * original.weightData().size());
}

TEST(FarmWire, CorruptOrMismatchedBlocksAreRefused) {
    const GaussianFilter gaussian;
    const BoxFilter box;
    const std::string data = pf::farm::encodeBlock(randomBlock(gaussian, 2));
    ImageBlock wrongSize(0, 0, 36, 23, &gaussian), wrongBorder(0, 0, 37, 23, &box), right(0, 0, 37, 23, &gaussian);
    EXPECT_THROW(pf::farm::decodeBlock(data, wrongSize), FarmError);
    EXPECT_THROW(pf::farm::decodeBlock(data, wrongBorder), FarmError);
    EXPECT_THROW(pf::farm::decodeBlock(data.substr(0, data.size() / 2), right), FarmError);
    EXPECT_THROW(pf::farm::decodeBlock(data.substr(0, 10), right), FarmError);
    std::string flipped = data;
    flipped[flipped.size() / 2] ^= 0x5a;
    EXPECT_THROW(pf::farm::decodeBlock(flipped, right), FarmError);
    ImageBlock infinite(0, 0, 37, 23, &gaussian);
    infinite.sumData()[5] = INFINITY;
    EXPECT_THROW(pf::farm::decodeBlock(pf::farm::encodeBlock(infinite), right), FarmError);
}

// The compressed body after a block's header, decompressed, changed by `edit` and compressed again (with the
// content checksum the codec writes, so that only the change itself can make the decoder refuse it).
std::string withBody(const std::string &data, size_t headerSize, const std::function<void(std::string &)> &edit) {
    const std::string_view frame = std::string_view(data).substr(headerSize);
    std::string body(ZSTD_getFrameContentSize(frame.data(), frame.size()), '\0');
    EXPECT_EQ(ZSTD_decompress(body.data(), body.size(), frame.data(), frame.size()), body.size());
    edit(body);
    std::string out = data.substr(0, headerSize);
    std::string compressed(ZSTD_compressBound(body.size()), '\0');
    ZSTD_CCtx *cctx = ZSTD_createCCtx();
    ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
    compressed.resize(ZSTD_compress2(cctx, compressed.data(), compressed.size(), body.data(), body.size()));
    ZSTD_freeCCtx(cctx);
    return out + compressed;
}

// Layout 2 (block_codec.cpp): a mask of the values whose bits are not all zero, then those values. Zeros,
// negative zeros and values next to them come back bit for bit, in a block whose value count is not a
// multiple of the mask's eight bits per byte; and the body is smaller than the values it stands for.
TEST(FarmWire, ZeroValuesAreLeftOutAndComeBackExactly) {
    const BoxFilter box;
    ImageBlock sparse(0, 0, 37, 23, &box);
    const size_t values = sparse.sumData().size() + sparse.weightData().size() + sparse.splatData().size();
    ASSERT_NE(values % 8, 0u);
    sparse.sumData()[0] = -0.0;
    sparse.sumData()[1] = 0x1p-1074;  // the smallest subnormal: one bit set
    sparse.weightData()[8] = 1.0;
    sparse.splatData()[sparse.splatData().size() - 1] = -2.5;
    for (size_t i = 16; i < 24; ++i) sparse.weightData()[i] = static_cast<double>(i);  // a whole mask byte set
    const std::string data = pf::farm::encodeBlock(sparse);
    EXPECT_EQ(data.substr(0, 4), "PFB2");
    ImageBlock decoded(0, 0, 37, 23, &box);
    decoded.sumData()[2] = 7.0;  // stale values where the data has zeros are overwritten
    pf::farm::decodeBlock(data, decoded);
    EXPECT_TRUE(sameStorage(sparse, decoded));
    EXPECT_TRUE(std::signbit(decoded.sumData()[0]));

    const std::string_view frame = std::string_view(data).substr(40);
    EXPECT_EQ(ZSTD_getFrameContentSize(frame.data(), frame.size()), (values + 7) / 8 + 12 * sizeof(double));
}

// A layout-2 body whose mask and values disagree, or whose mask marks values past the block's end, is refused
// with a FarmError that says so.
TEST(FarmWire, InconsistentMasksAreRefused) {
    const GaussianFilter gaussian;
    const ImageBlock original = randomBlock(gaussian, 5);
    const size_t values = original.sumData().size() + original.weightData().size() + original.splatData().size();
    ASSERT_NE(values % 8, 0u);
    const size_t maskSize = (values + 7) / 8;
    const std::string data = pf::farm::encodeBlock(original);
    const auto refused = [&](const std::string &bad, const std::string &message) {
        ImageBlock block(0, 0, 37, 23, &gaussian);
        try {
            pf::farm::decodeBlock(bad, block);
            ADD_FAILURE() << "accepted; expected: " << message;
        } catch (const FarmError &e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    };
    refused(withBody(data, 40, [&](std::string &b) { b[maskSize - 1] = static_cast<char>(0xff); }),
            "mask bits beyond the last value");
    refused(withBody(data, 40,
                     [&](std::string &b) {
                         for (size_t i = 0; i < maskSize; ++i)
                             if (b[i] != 0) {
                                 b[i] = static_cast<char>(b[i] & (b[i] - 1));  // one set bit fewer
                                 return;
                             }
                     }),
            "mask and values disagree");
    refused(withBody(data, 40, [&](std::string &b) { b.resize(b.size() - 8); }), "mask and values disagree");
    refused(withBody(data, 40, [&](std::string &b) { b.resize(b.size() - 3); }), "corrupt or truncated data");
    refused(withBody(data, 40, [&](std::string &b) { b.resize(maskSize - 1); }), "corrupt or truncated data");
}

// Layout 1, which workers and masters wrote before layout 2 (all values, byte-shuffled), is still read: a master
// updated in the middle of a job decodes the checkpoints and results written before.
TEST(FarmWire, LayoutOneBlocksStillDecode) {
    const GaussianFilter gaussian;
    const ImageBlock original = randomBlock(gaussian, 6);
    std::vector<double> all;
    for (const std::span<const double> a : {original.sumData(), original.weightData(), original.splatData()})
        all.insert(all.end(), a.begin(), a.end());
    std::string shuffled(all.size() * sizeof(double), '\0');
    for (size_t i = 0; i < all.size(); ++i)
        for (size_t b = 0; b < sizeof(double); ++b)
            shuffled[b * all.size() + i] = reinterpret_cast<const char *>(&all[i])[b];
    std::string layoutOne = pf::farm::encodeBlock(original);
    layoutOne[3] = '1';
    layoutOne = withBody(layoutOne, 40, [&](std::string &b) { b = shuffled; });
    ImageBlock decoded(0, 0, 37, 23, &gaussian);
    pf::farm::decodeBlock(layoutOne, decoded);
    EXPECT_TRUE(sameStorage(original, decoded));

    std::string unknown = pf::farm::encodeBlock(original);
    unknown[3] = '3';
    EXPECT_THROW(pf::farm::decodeBlock(unknown, decoded), FarmError);
}

// A chain task's film as tiles (image/splat_tiles.h): deposits around one spot, as a burst task's lie
// around its band of pixels.
ImageBlock randomTiles(const ReconstructionFilter &filter, uint32_t seed) {
    ImageBlock b(0, 0, 200, 150, &filter, BlockStorage::Tiles);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < 2000; ++i)
        b.splat(Vec2(40 + 50 * u(rng), 70 + 30 * u(rng)), Spectrum(u(rng), u(rng) * 1e-7, u(rng) * 1e9));
    b.splat(Vec2(1, 1), Spectrum(std::nan(""), 0, 0));  // counted as invalid, which must travel too
    return b;
}

bool sameTiles(const ImageBlock &a, const ImageBlock &b) {
    const SplatTiles &x = *a.tiles(), &y = *b.tiles();
    if (x.tileCount() != y.tileCount() || a.invalidSamples() != b.invalidSamples()) return false;
    for (size_t t = 0; t < x.tileCount(); ++t) {
        const std::span<const double> p = x.tile(t), q = y.tile(t);
        if (p.size() != q.size() || std::memcmp(p.data(), q.data(), p.size() * sizeof(double)) != 0) return false;
    }
    return true;
}

// Only the tiles present travel, bit for bit, and the decoded block has exactly those tiles.
TEST(FarmWire, TilesRoundTripBitForBit) {
    const GaussianFilter filter;
    const ImageBlock original = randomTiles(filter, 3);
    const std::string data = pf::farm::encodeBlock(original);
    ImageBlock decoded(0, 0, 200, 150, &filter, BlockStorage::Tiles);
    decoded.splat(Vec2(190, 140), Spectrum(1.0));  // a tile the data does not list
    pf::farm::decodeBlock(data, decoded);
    EXPECT_TRUE(sameTiles(original, decoded));
    EXPECT_EQ(decoded.invalidSamples(), 1u);
    EXPECT_EQ(decoded.storedValues(), original.storedValues());
    constexpr size_t kTile = SplatTiles::kSize;
    EXPECT_LT(original.storedValues(), original.tiles()->tileCount() * 3 * kTile * kTile / 4);
    // (No bound on the bytes: zstd shrinks a dense block's runs of zeros to almost nothing too, so the same
    // deposits take about as many bytes either way; what tiles save is the time and memory spent on zeros.)

    const ImageBlock empty(0, 0, 200, 150, &filter, BlockStorage::Tiles);
    pf::farm::decodeBlock(pf::farm::encodeBlock(empty), decoded);
    EXPECT_TRUE(sameTiles(empty, decoded));
    EXPECT_EQ(decoded.storedValues(), 0u);
}

// Every malformed tile block is a FarmError that says what is wrong, never a crash or a partial merge.
TEST(FarmWire, MalformedTilesAreRefused) {
    const GaussianFilter gaussian;
    const BoxFilter box;
    const ImageBlock original = randomTiles(gaussian, 4);
    const std::string data = pf::farm::encodeBlock(original);
    const auto refused = [&](const std::string &bad, ImageBlock block, const std::string &message) {
        try {
            pf::farm::decodeBlock(bad, block);
            ADD_FAILURE() << "accepted; expected: " << message;
        } catch (const FarmError &e) {
            EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
        }
    };
    const auto tilesBlock = [&] { return ImageBlock(0, 0, 200, 150, &gaussian, BlockStorage::Tiles); };
    // The header: magic (4 bytes), offset, size and border (5 x 4), tile size and tiles listed (2 x 4), invalid
    // samples (8); then the list of uint32 tile indices.
    constexpr size_t kTileSizeAt = 24, kCountAt = 28, kListAt = 40;
    const auto u32 = [&](const std::string &d, size_t at) {
        uint32_t v;
        std::memcpy(&v, d.data() + at, sizeof v);
        return v;
    };
    const auto withU32 = [&](size_t at, uint32_t v) {
        std::string d = data;
        std::memcpy(d.data() + at, &v, sizeof v);
        return d;
    };
    const uint32_t listed = u32(data, kCountAt), tileCount = static_cast<uint32_t>(original.tiles()->tileCount());
    ASSERT_GT(listed, 2u);
    ASSERT_GT(u32(data, kListAt), 0u);  // the deposits lie away from the film's first tile

    refused(data.substr(0, 3), tilesBlock(), "truncated header");
    refused(data.substr(0, 20), tilesBlock(), "truncated header");
    refused(data.substr(0, kListAt + 4), tilesBlock(), "truncated tile list");
    refused(data.substr(0, data.size() - 10), tilesBlock(), "corrupt or truncated data");
    refused(withU32(kListAt, tileCount + 5), tilesBlock(), "out of range");
    refused(withU32(kListAt + 4, u32(data, kListAt)), tilesBlock(), "listed twice");
    refused(withU32(kListAt, u32(data, kListAt + 4)), tilesBlock(), "listed twice");
    refused(withU32(kListAt + 4, u32(data, kListAt) - 1), tilesBlock(), "out of order");
    refused(withU32(kCountAt, tileCount + 1), tilesBlock(), "tiles listed, the film has");
    refused(withU32(kTileSizeAt, 16), tilesBlock(),
            "tiles of 16 pixels, expected " + std::to_string(SplatTiles::kSize));
    // One tile fewer in the list than in the body: the body's size no longer matches.
    std::string shorter = withU32(kCountAt, listed - 1);
    shorter.erase(kListAt + 4 * (listed - 1), 4);
    refused(shorter, tilesBlock(), "corrupt or truncated data");
    std::string flipped = data;
    flipped[flipped.size() - 20] ^= 0x5a;
    refused(flipped, tilesBlock(), "film block");
    refused(data, ImageBlock(0, 0, 201, 150, &gaussian, BlockStorage::Tiles), "layout");
    refused(data, ImageBlock(0, 0, 200, 150, &box, BlockStorage::Tiles), "layout");
    refused(data, ImageBlock(0, 0, 200, 150, &gaussian), "tiles where a dense block was expected");
    refused(pf::farm::encodeBlock(ImageBlock(0, 0, 200, 150, &gaussian)), tilesBlock(),
            "a dense block where tiles were expected");
    ImageBlock infinite = randomTiles(gaussian, 4);
    infinite.tiles()->allocate(0)[7] = INFINITY;
    refused(pf::farm::encodeBlock(infinite), tilesBlock(), "non-finite value");
    refused("PFX1" + data.substr(4), tilesBlock(), "not a pathfarm block");
}

// Burst tasks and the luminance pilot on the wire (render/burst.h, render/pilot.h): a task's pass, plan, W
// and what the pilot tuned (λ, medium dtheta) round-trip exactly, and a worker refuses a malformed plan or a bad
// W, λ or dtheta with a FarmError (the master refuses a pilot result with a bad λ or dtheta alike) rather than
// dividing by zero later.
TEST(FarmWire, BurstTasksRoundTripAndMalformedOnesAreRefused) {
    pf::ChainTask task;
    task.index = 17;
    task.mutations = 100;
    task.tuning = {8.5, 0.03125};
    pf::BurstPlan plan;
    plan.interleave = 7;
    plan.blocks = 3;
    plan.chainsPerPixel = 0.125;
    task.burst = pf::BurstPass{11, 2, 0.25, plan};
    const pf::ChainTask back = pf::farm::fromProto(pf::farm::toProto(task));
    ASSERT_TRUE(back.burst.has_value());
    EXPECT_EQ(back.index, 17u);
    EXPECT_EQ(back.tuning, task.tuning);
    EXPECT_EQ(back.burst->pass, 11u);
    EXPECT_EQ(back.burst->block, 2u);
    EXPECT_EQ(back.burst->meanLuminance, 0.25);
    EXPECT_EQ(back.burst->plan.interleave, 7u);
    EXPECT_EQ(back.burst->plan.blocks, 3u);
    EXPECT_EQ(back.burst->plan.chainsPerPixel, 0.125);

    const auto refused = [&](const std::function<void(pathfarm::v1::ChainTask &)> &spoil) {
        pathfarm::v1::ChainTask wire = pf::farm::toProto(task);
        spoil(wire);
        EXPECT_THROW(pf::farm::fromProto(wire), FarmError) << wire.DebugString();
    };
    refused([](auto &w) { w.mutable_burst()->set_interleave(0); });
    refused([](auto &w) { w.mutable_burst()->set_blocks(0); });
    refused([](auto &w) { w.mutable_burst()->set_block(3); });
    refused([](auto &w) { w.mutable_burst()->set_chains_per_pixel(0); });
    refused([](auto &w) { w.mutable_burst()->set_chains_per_pixel(std::nan("")); });
    refused([](auto &w) { w.mutable_burst()->set_mean_luminance(-1); });
    refused([](auto &w) { w.mutable_burst()->set_mean_luminance(INFINITY); });
    refused([](auto &w) { w.set_lambda(-2); });
    refused([](auto &w) { w.set_medium_angle(-0.5); });
    refused([](auto &w) { w.set_medium_angle(4); });  // beyond pi
    refused([](auto &w) { w.set_medium_angle(std::nan("")); });

    pf::SeedingResult pilot;
    pilot.depthLuminance = {0.5, 0.25};
    pilot.samples = 15000;
    pilot.tuning = {9.25, 0.0625};
    const pf::SeedingTask pilotTask{0, 0, 15000};
    const pf::SeedingTask wireTask = pf::farm::fromProto([&] {
        pathfarm::v1::SeedingTask t;
        pf::farm::toProto(pilotTask, t);
        return t;
    }());
    EXPECT_EQ(wireTask.pilotSamples, 15000u);
    const auto scene = pf::loadScene(writeTestScene(tempDir("wire-pilot"), 8, 1));
    const pf::Film &film = scene->sensor().film();
    const pf::SeedingResult decoded =
        pf::farm::decodeSeedingResult(pf::farm::encodeSeedingResult(pilot), film, wireTask);
    EXPECT_EQ(decoded.tuning, pilot.tuning);
    EXPECT_EQ(decoded.depthLuminance, pilot.depthLuminance);
    for (const pf::ManifoldTuning bad :
         {pf::ManifoldTuning{std::nan(""), 0}, pf::ManifoldTuning{1, -1}, pf::ManifoldTuning{1, INFINITY}}) {
        pilot.tuning = bad;
        EXPECT_THROW(pf::farm::decodeSeedingResult(pf::farm::encodeSeedingResult(pilot), film, wireTask), FarmError);
    }
}

TEST(FarmWire, SceneFilesAreCollectedThroughIncludesAndDefines) {
    const std::string dir = tempDir("farm-wire-collect");
    const std::string scene = writeTestScene(dir, 8, 1);
    writeFile(dir, "unused.obj", "v 0 0 0\n");
    writeFile(dir, "meshes/alt.obj", "v 0 0 0\n");
    writeFile(fs::path(dir).parent_path().string(), "outside.obj", "v 0 0 0\n");
    const std::string withDefine = writeFile(dir, "defined.xml", R"(<scene version="0.6.0">
  <default name="mesh" value="floor"/>
  <shape type="obj"><string name="filename" value="meshes/$mesh.obj"/></shape>
  <shape type="obj"><string name="filename" value="../outside.obj"/></shape>
  <include filename="parts/light.xml"/>
</scene>
)");
    EXPECT_EQ(pf::farm::collectSceneFiles(scene, {}),
              (std::vector<std::string>{"scene.xml", "parts/light.xml", "meshes/floor.obj"}));
    EXPECT_EQ(pf::farm::collectSceneFiles(withDefine, {}),
              (std::vector<std::string>{"defined.xml", "meshes/floor.obj", "parts/light.xml"}));
    EXPECT_EQ(pf::farm::collectSceneFiles(withDefine, {{"mesh", "alt"}}),
              (std::vector<std::string>{"defined.xml", "meshes/alt.obj", "parts/light.xml"}));
}

TEST(FarmWire, ManifestsRefuseEntriesOutsideTheBundle) {
    auto manifest = [](const std::vector<std::string> &paths) {
        pathfarm::v1::BundleManifest m;
        m.set_scene_file(paths.front());
        for (const std::string &p : paths) {
            auto *e = m.add_entries();
            e->set_path(p);
            e->set_size(1);
            e->set_hash(pf::farm::hashHex64("x"));
        }
        return m;
    };
    EXPECT_NO_THROW(pf::farm::validateManifest(manifest({"scene.xml", "meshes/a.obj", "a..b/c"}), 100));
    for (const char *bad : {"../a", "/abs", "a/../../b", "a/./b", "a//b", "a\\b", "C:/x", "", "a/"})
        EXPECT_THROW(pf::farm::validateManifest(manifest({"scene.xml", bad}), 100), FarmError) << bad;
    EXPECT_THROW(pf::farm::validateManifest(manifest({"scene.xml", "scene.xml"}), 100), FarmError);
    EXPECT_THROW(pf::farm::validateManifest(manifest({"scene.xml", "b"}), 1), FarmError);
    auto noScene = manifest({"scene.xml"});
    noScene.set_scene_file("other.xml");
    EXPECT_THROW(pf::farm::validateManifest(noScene, 100), FarmError);
}

TEST(FarmWire, BundlesAreStoredOnlyWhenComplete) {
    const std::string src = tempDir("farm-wire-src");
    const std::string scene = writeTestScene(src, 8, 1);
    const auto manifest = pf::farm::makeManifest(src, "scene.xml", pf::farm::collectSceneFiles(scene, {}));
    std::vector<pathfarm::v1::BundleChunk> chunks;
    pf::farm::streamBundle(src, manifest, 64, [&](const pathfarm::v1::BundleChunk &c) {
        chunks.push_back(c);
        return true;
    });
    EXPECT_GT(chunks.size(), 3u);  // small chunks cross file boundaries

    pf::farm::BundleStore store(tempDir("farm-wire-store"), 1 << 20);
    auto replay = [&](std::vector<pathfarm::v1::BundleChunk> list) {
        size_t i = 0;
        return store.receive([&](pathfarm::v1::BundleChunk &c) {
            if (i == list.size()) return false;
            c = list[i++];
            return true;
        });
    };
    auto corrupted = chunks;
    corrupted.back().mutable_data()->back() ^= 1;
    EXPECT_THROW(replay(corrupted), FarmError);
    EXPECT_FALSE(store.has(pf::farm::bundleHash(manifest)));
    const std::string hash = replay(chunks);
    EXPECT_EQ(hash, pf::farm::bundleHash(manifest));
    ASSERT_TRUE(store.has(hash));
    EXPECT_EQ(pf::farm::readFile(store.dir(hash) + "/meshes/floor.obj"), pf::farm::readFile(src + "/meshes/floor.obj"));
    EXPECT_FALSE(store.has("../" + hash));
    EXPECT_THROW(store.dir("../etc"), FarmError);
}

}  // namespace
}  // namespace pf::test::farm
