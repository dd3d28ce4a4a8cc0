// A time budget's partial last pass (render/image_task.h, mergeCoveredPixels): one more sample in the first tiles
// of the film. Pixels whose filter footprint lies wholly in those tiles get it, bit for bit as a whole pass would
// give it; the others keep the whole passes' bits. Light tracing's splats count every light path traced, and the
// image stays an unbiased estimate: BDPT's partial renders agree with whole-pass renders, in the covered part and
// in the uncovered part, where a splat scale that ignored the partial pass's light paths would be too bright.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <tuple>
#include <vector>

#include "integrators/integrator.h"
#include "render/image_task.h"
#include "support/agreement.h"

namespace pf::test {
namespace {

const SamplingIntegrator &sampling(const Integrator &i) { return dynamic_cast<const SamplingIntegrator &>(i); }

// The film's tiles at 64² are 8², eight to a row (image_task.cpp: at least 64 tiles, 32² down to 8²).
constexpr int kRes = 64, kTile = 8;

bool coveredPixel(int x, int y, int64_t tiles) { return (y / kTile) * (kRes / kTile) + x / kTile < tiles; }

// A task reports each tile's rendering time in the film's tile order (what sizes a partial pass), and a partial
// task only its own tiles'.
TEST(PartialPass, ATaskReportsItsTilesTimes) {
    auto scene = loadScene((std::filesystem::path(PATHFARM_SOURCE_DIR) / "scenes/cornell-box/scene.xml").string());
    scene->resizeFilm(kRes, kRes);
    const auto path = createIntegrator("path", scene->integratorProperties(), false);
    const ImageTaskResult whole = runImageTask(*scene, sampling(*path), 5, ImageTask{0, 1}, 2);
    ASSERT_EQ(whole.tileSeconds.size(), static_cast<size_t>(filmTiles(scene->sensor().film())));
    for (const float s : whole.tileSeconds) EXPECT_GT(s, 0.0f);
    const ImageTaskResult part = runImageTask(*scene, sampling(*path), 5, ImageTask{1, 1, 20}, 2);
    ASSERT_EQ(part.tileSeconds.size(), size_t{20});
    for (const float s : part.tileSeconds) EXPECT_GT(s, 0.0f);
}

TEST(PartialPass, PixelsWithAWhollyCoveredFootprintGetTheSampleAndTheOthersKeepTheirBits) {
    // cornell-box as shipped: the tent filter reaches one pixel beyond a sample's own.
    auto scene = loadScene((std::filesystem::path(PATHFARM_SOURCE_DIR) / "scenes/cornell-box/scene.xml").string());
    scene->resizeFilm(kRes, kRes);
    const Film &film = scene->sensor().film();
    ASSERT_EQ(film.filter().radius(), 1.0);
    ASSERT_EQ(filmTiles(film), (kRes / kTile) * (kRes / kTile));
    const auto path = createIntegrator("path", scene->integratorProperties(), false);
    constexpr int64_t kTiles = 20;  // two rows of tiles and half of the third

    ImageBlock two = makeFilmBlock(*scene), three = makeFilmBlock(*scene), partial = makeFilmBlock(*scene);
    const ImageTaskResult first = runImageTask(*scene, sampling(*path), 5, ImageTask{0, 2}, 2);
    two.merge(first.block);
    three.merge(first.block);
    partial.merge(first.block);
    three.merge(runImageTask(*scene, sampling(*path), 5, ImageTask{2, 1}, 2).block);
    const ImageTaskResult last = runImageTask(*scene, sampling(*path), 5, ImageTask{2, 1, kTiles}, 2);
    EXPECT_EQ(last.pixels, static_cast<uint64_t>(kTiles * kTile * kTile));
    EXPECT_EQ(last.samples, last.pixels);
    mergeCoveredPixels(partial, last.block, film, kTiles);

    const Bitmap a = film.develop(two, 0.5), b = film.develop(three, 1.0 / 3.0), c = film.develop(partial, 0.4);
    int gained = 0, kept = 0;
    for (int y = 0; y < kRes; ++y)
        for (int x = 0; x < kRes; ++x) {
            bool footprint = true;
            for (int qy = std::max(0, y - 1); qy <= std::min(kRes - 1, y + 1); ++qy)
                for (int qx = std::max(0, x - 1); qx <= std::min(kRes - 1, x + 1); ++qx)
                    footprint = footprint && coveredPixel(qx, qy, kTiles);
            const Bitmap &expected = footprint ? b : a;
            const size_t i = (static_cast<size_t>(y) * kRes + x) * 3;
            for (size_t ch = 0; ch < 3; ++ch)
                ASSERT_EQ(c.rgb[i + ch], expected.rgb[i + ch]) << x << ", " << y << (footprint ? " covered" : "");
            (footprint ? gained : kept) += 1;
        }
    // Rows 0-14 wholly, rows 15-22 over x 0-30; a covered pixel next to an uncovered one keeps its bits.
    EXPECT_EQ(gained, 15 * kRes + 8 * 31);
    EXPECT_EQ(kept, kRes * kRes - gained);
}

// Independent estimates, one per seed: their mean and its standard error.
struct SeedStats {
    std::vector<double> values;
    void add(double v) { values.push_back(v); }
    double mean() const {
        double sum = 0;
        for (const double v : values) sum += v;
        return sum / static_cast<double>(values.size());
    }
    double stderrOfMean() const {
        const double m = mean();
        double sum2 = 0;
        for (const double v : values) sum2 += (v - m) * (v - m);
        const double n = static_cast<double>(values.size());
        return std::sqrt(sum2 / (n - 1) / n);
    }
};

// Per seed, the mean luminance of the covered tiles and of the rest of the film.
struct Halves {
    SeedStats covered, uncovered;
};

Halves halves(const std::vector<Bitmap> &images, int64_t tiles) {
    Halves h;
    for (const Bitmap &img : images) {
        double in = 0, out = 0;
        int nIn = 0, nOut = 0;
        for (int y = 0; y < kRes; ++y)
            for (int x = 0; x < kRes; ++x) {
                const double l = img.get(x, y).luminance();
                if (coveredPixel(x, y, tiles)) {
                    in += l;
                    ++nIn;
                } else {
                    out += l;
                    ++nOut;
                }
            }
        h.covered.add(in / nIn);
        h.uncovered.add(out / nOut);
    }
    return h;
}

TEST(PartialPass, BDPTStaysUnbiased) {
    auto scene = loadSharedScene("cornell-box", kRes);
    const Film &film = scene->sensor().film();
    const auto bdpt = createIntegrator("bdpt", scene->integratorProperties(), false);
    constexpr int kSeeds = 32;
    constexpr int64_t kTiles = 32;  // the upper half of the film
    std::vector<Bitmap> partialImages, wholeImages;
    for (int k = 0; k < kSeeds; ++k) {
        const uint64_t seed = 7919 * static_cast<uint64_t>(k + 1);
        ImageBlock block = makeFilmBlock(*scene);
        const ImageTaskResult first = runImageTask(*scene, sampling(*bdpt), seed, ImageTask{0, 1}, 2);
        block.merge(first.block);
        const ImageTaskResult last = runImageTask(*scene, sampling(*bdpt), seed, ImageTask{1, 1, kTiles}, 2);
        mergeCoveredPixels(block, last.block, film, kTiles);
        // pixels / light paths: 1 / 1.5.
        const double scale = static_cast<double>(kRes * kRes) / static_cast<double>(first.samples + last.samples);
        EXPECT_DOUBLE_EQ(scale, 1.0 / 1.5);
        partialImages.push_back(film.develop(block, scale));

        RenderOptions opt;
        opt.spp = 2;
        opt.seed = seed + 1;
        opt.threads = 2;
        RenderStats stats;
        wholeImages.push_back(bdpt->render(*scene, opt, stats));
    }
    const Halves p = halves(partialImages, kTiles), w = halves(wholeImages, kTiles);
    for (const auto &[what, tested, reference] :
         {std::tuple{"covered", p.covered, w.covered}, std::tuple{"uncovered", p.uncovered, w.uncovered}}) {
        const double z =
            (tested.mean() - reference.mean()) / std::sqrt(tested.stderrOfMean() * tested.stderrOfMean() +
                                                           reference.stderrOfMean() * reference.stderrOfMean());
        std::printf("%s: partial %.5f +- %.5f, whole passes %.5f +- %.5f, z %.2f\n", what, tested.mean(),
                    tested.stderrOfMean(), reference.mean(), reference.stderrOfMean(), z);
        EXPECT_LT(std::abs(z), 4.0) << what;
        // The test can tell: the standard error is under 1% of the mean.
        EXPECT_LT(reference.stderrOfMean(), 0.01 * reference.mean()) << what;
    }
}

}  // namespace
}  // namespace pf::test
