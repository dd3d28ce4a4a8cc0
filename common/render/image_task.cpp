#include "render/image_task.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <numeric>
#include <thread>
#include <vector>

#include "core/ld_sampler.h"
#include "scene/scene.h"

namespace pf {

namespace {

// Tiles are the unit of work a thread takes. 32² keeps a tile's block and splat list cheap against its
// samples; smaller films get smaller tiles, at least 64 of them, so that a pass of a 64² film does not leave
// one of two threads idle while the other finishes the last of four tiles (7% of two cores' time at 64² with
// 32² tiles). The size depends on the film alone, never on the thread count: tiles are merged in their
// order, so the same tiles give the farm's workers and the embedded render the same bits.
constexpr int kMaxTileSize = 32;
constexpr int kMinTileSize = 8;
constexpr int64_t kMinTiles = 64;

int tileSize(int width, int height) {
    int size = kMaxTileSize;
    const auto tiles = [&](int s) { return int64_t{(width + s - 1) / s} * ((height + s - 1) / s); };
    while (size > kMinTileSize && tiles(size) < kMinTiles) size /= 2;
    return size;
}

// Samples per pixel in one task. A task's cost to the farm's master (decoding and merging a film, bytes on
// the wire) does not depend on its samples, so tasks grow as a job progresses: the first samples come in
// small tasks (a responsive progress bar and live preview, fine-grained scheduling, cheap retries, and a
// first measure of the job's pace before a time budget commits to larger ones), and later each task is the
// largest power of two up to 1/8 of the samples before it, so that a long job's task count grows only
// logarithmically until the largest size. The bounds are in pixel samples, so that a task's cost does not
// grow with the film: 8 and 256 spp up to 256², 1 and 16 spp at 1024² (with 8 spp, a 1024² BDPT job's first
// task took 45 s on two cores, and a farm job under --time 20 ran 52 s). The sizes depend on the film and the
// first sample alone, so every budget, a time budget included, takes a prefix of the same sequence of tasks.
constexpr int64_t kMinSamplesPerTask = 8;
constexpr int64_t kMaxSamplesPerTask = 256;
constexpr int64_t kBoundPixels = 256 * 256;
constexpr int64_t kGrowthDivisor = 8;
// A time budget's passes take about this fraction of it each (timedPassSize).
constexpr double kPassesPerBudget = 64;

// `limit` halved until a task of that many samples per pixel holds no more pixel samples than `limit` does
// at 256², but never below 1.
int64_t scaledBound(int64_t limit, int64_t pixels) {
    int64_t size = limit;
    while (size > 1 && size * pixels > limit * kBoundPixels) size /= 2;
    return size;
}

struct Tile {
    int x, y, w, h;
};

std::vector<Tile> makeTiles(int width, int height) {
    const int size = tileSize(width, height);
    std::vector<Tile> tiles;
    for (int y = 0; y < height; y += size)
        for (int x = 0; x < width; x += size)
            tiles.push_back({x, y, std::min(size, width - x), std::min(size, height - y)});
    return tiles;
}

}  // namespace

ImageBlock makeFilmBlock(const Scene &scene, BlockStorage storage) {
    const Film &film = scene.sensor().film();
    return ImageBlock(0, 0, film.cropWidth(), film.cropHeight(), &film.filter(), storage);
}

int64_t filmPixels(const Film &film) { return int64_t{film.cropWidth()} * film.cropHeight(); }

int64_t filmTiles(const Film &film) {
    return static_cast<int64_t>(makeTiles(film.cropWidth(), film.cropHeight()).size());
}

int64_t tilePixels(const Film &film, int64_t tiles) {
    int64_t pixels = 0;
    const std::vector<Tile> all = makeTiles(film.cropWidth(), film.cropHeight());
    for (size_t i = 0; i < all.size() && static_cast<int64_t>(i) < tiles; ++i) pixels += int64_t{all[i].w} * all[i].h;
    return pixels;
}

std::vector<char> partialPassFootprints(const Film &film, int64_t tiles) {
    const int w = film.cropWidth(), h = film.cropHeight();
    // covered[y][x]: crop pixel (x, y) lies in one of the first `tiles` tiles.
    std::vector<char> covered(static_cast<size_t>(w) * h, 0);
    const std::vector<Tile> all = makeTiles(w, h);
    for (size_t i = 0; i < all.size() && static_cast<int64_t>(i) < tiles; ++i)
        for (int y = all[i].y; y < all[i].y + all[i].h; ++y)
            std::fill_n(covered.begin() + static_cast<size_t>(y) * w + all[i].x, all[i].w, 1);
    // A sample at most half a pixel from its pixel's centre reaches pixels up to radius + 1/2 away.
    const int reach = static_cast<int>(std::floor(film.filter().radius() + 0.5));
    std::vector<char> footprint(covered.size(), 0);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool inside = true;
            for (int qy = std::max(0, y - reach); inside && qy <= std::min(h - 1, y + reach); ++qy)
                for (int qx = std::max(0, x - reach); inside && qx <= std::min(w - 1, x + reach); ++qx)
                    inside = covered[static_cast<size_t>(qy) * w + qx] != 0;
            footprint[static_cast<size_t>(y) * w + x] = inside;
        }
    return footprint;
}

void mergeCoveredPixels(ImageBlock &film, ImageBlock pass, const Film &filmDesc, int64_t tiles) {
    const int w = filmDesc.cropWidth(), h = filmDesc.cropHeight();
    const std::vector<char> footprint = partialPassFootprints(filmDesc, tiles);
    // The block's border (pixels outside the crop window that samples reach) is never covered: no task samples
    // there.
    const int b = pass.border();
    std::span<double> sums = pass.sumData(), weights = pass.weightData();
    for (int y = -b; y < h + b; ++y)
        for (int x = -b; x < w + b; ++x) {
            if (x >= 0 && y >= 0 && x < w && y < h && footprint[static_cast<size_t>(y) * w + x]) continue;
            const size_t i = static_cast<size_t>(y + b) * (w + 2 * b) + (x + b);
            sums[3 * i] = sums[3 * i + 1] = sums[3 * i + 2] = 0.0;
            weights[i] = 0.0;
        }
    film.merge(pass);
}

double splatScale(int64_t pixels, int64_t spp, int64_t partialPixels) {
    const double paths = static_cast<double>(spp) * static_cast<double>(pixels) + static_cast<double>(partialPixels);
    return paths > 0 ? static_cast<double>(pixels) / paths : 0.0;
}

std::string partialPassSummary(double share) {
    if (!(share > 0)) return "";
    char text[48];
    std::snprintf(text, sizeof text, " + 1 in %.0f%% of pixels", 100.0 * share);
    return text;
}

int64_t imageTaskSize(int64_t spp, int64_t firstSample, int64_t pixels) {
    const int64_t largest = scaledBound(kMaxSamplesPerTask, pixels);
    int64_t size = scaledBound(kMinSamplesPerTask, pixels);
    while (size < largest && 2 * size <= firstSample / kGrowthDivisor) size *= 2;
    return std::min(size, spp - firstSample);
}

int64_t timedPartialTiles(double budget, double elapsed, const ImageTask &last, double lastSeconds, int64_t tiles,
                          std::span<const float> tileSeconds) {
    if (last.sampleCount <= 0 || !(lastSeconds > 0) || tiles <= 0) return 0;
    const double perSample = lastSeconds / static_cast<double>(last.sampleCount), left = budget - elapsed;
    const double total = std::accumulate(tileSeconds.begin(), tileSeconds.end(), 0.0);
    if (tileSeconds.size() != static_cast<size_t>(tiles) || !(total > 0)) {
        const double fits = std::floor(left / (perSample / static_cast<double>(tiles)));
        return fits >= 1 ? static_cast<int64_t>(std::min(fits, static_cast<double>(tiles - 1))) : 0;
    }
    // The largest n whose tiles' share of a sample per pixel fits.
    int64_t n = 0;
    for (double share = 0; n < tiles - 1; ++n) {
        share += tileSeconds[static_cast<size_t>(n)] / total;
        if (perSample * share > left) break;
    }
    return n;
}

int64_t timedPassSize(double budget, double elapsed, const ImageTask &last, double lastSeconds) {
    if (last.sampleCount <= 0) return 1;
    const double perSample = lastSeconds / static_cast<double>(last.sampleCount);
    const double twice = 2.0 * static_cast<double>(last.sampleCount);
    if (!(perSample > 0)) return static_cast<int64_t>(twice);
    const double fits = std::floor((budget - elapsed) / perSample);
    const double target = std::max(1.0, std::floor(budget / kPassesPerBudget / perSample));
    const double size = std::min({fits, target, twice});
    return size >= 1 ? static_cast<int64_t>(size) : 0;
}

ImageTaskResult runImageTask(const Scene &scene, const SamplingIntegrator &integrator, uint64_t seed,
                             const ImageTask &task, int threads, const SampleSequence *sequence) {
    const auto start = std::chrono::steady_clock::now();
    const Film &film = scene.sensor().film();
    std::vector<Tile> tiles = makeTiles(film.cropWidth(), film.cropHeight());
    if (task.tiles >= 0 && task.tiles < static_cast<int64_t>(tiles.size()))
        tiles.resize(static_cast<size_t>(task.tiles));
    const ReconstructionFilter *filter = &film.filter();

    std::vector<ImageBlock> blocks;
    blocks.reserve(tiles.size());
    for (const Tile &t : tiles) blocks.emplace_back(t.x, t.y, t.w, t.h, filter);
    // Splats (light tracing's t = 1 strategies land anywhere on the film) are added to the result in tile
    // order, so that the image does not depend on which thread rendered which tile; a tile's list is added
    // and freed as soon as every tile before it is done, so only the tiles in flight hold theirs (kept to
    // the end, a 1024² BDPT task of 8 spp held over 1 GB of them, and one of 256 spp would hold ~30 GB).
    ImageTaskResult result{makeFilmBlock(scene)};
    result.tileSeconds.assign(tiles.size(), 0.0f);
    std::vector<SplatList> splats(tiles.size());
    std::vector<char> tileDone(tiles.size(), 0);
    size_t splatted = 0;  // tiles whose splats are in result.block
    std::mutex splatMu;
    const auto finishTile = [&](size_t i) {
        const std::lock_guard<std::mutex> lock(splatMu);
        tileDone[i] = 1;
        // In list order (the same bits whatever the threads did), with each splat's pixels asked for a few splats
        // ahead (ImageBlock::prefetchSplat).
        constexpr size_t kAhead = 8;
        for (; splatted < tiles.size() && tileDone[splatted]; ++splatted) {
            const SplatList &list = splats[splatted];
            for (size_t k = 0; k < list.size(); ++k) {
                if (k + kAhead < list.size()) result.block.prefetchSplat(list[k + kAhead].raster);
                if (list[k].value.isFinite()) result.block.splat(list[k].raster, list[k].value);
            }
            SplatList().swap(splats[splatted]);
        }
    };
    std::atomic<size_t> next{0};
    std::atomic<uint64_t> rays{0};
    auto worker = [&]() {
        const uint64_t rays0 = Scene::threadRayCount();
        const std::unique_ptr<PixelSampler> pixelSampler =
            makePixelSampler(sequence ? *sequence : scene.sensor().sampleSequence(), film.width(), film.height());
        PixelSampler &sampler = *pixelSampler;
        for (size_t i; (i = next.fetch_add(1)) < tiles.size();) {
            const auto tileStart = std::chrono::steady_clock::now();
            const Tile &t = tiles[i];
            for (int y = t.y; y < t.y + t.h; ++y)
                for (int x = t.x; x < t.x + t.w; ++x) {
                    const uint64_t pixel = static_cast<uint64_t>(film.cropY() + y) * film.width() + film.cropX() + x;
                    for (int64_t s = task.firstSample; s < task.firstSample + task.sampleCount; ++s) {
                        sampler.start(seed, pixel, static_cast<uint64_t>(s));
                        const Vec2 raster = Vec2(x, y) + sampler.next2D();
                        Spectrum L = integrator.sample(scene, sampler, raster, splats[i]);
                        // A NaN or infinite sample would poison a whole filter footprint; it signals a
                        // bug, so it is dropped here rather than hidden in the image.
                        if (!L.isFinite()) L = Spectrum();
                        blocks[i].put(raster, L);
                    }
                }
            result.tileSeconds[i] = std::chrono::duration<float>(std::chrono::steady_clock::now() - tileStart).count();
            finishTile(i);
        }
        rays.fetch_add(Scene::threadRayCount() - rays0);
    };
    std::vector<std::thread> pool;
    for (int k = 1; k < threads; ++k) pool.emplace_back(worker);
    worker();
    for (auto &th : pool) th.join();

    for (const ImageBlock &b : blocks) result.block.merge(b);
    for (const Tile &t : tiles) result.pixels += static_cast<uint64_t>(t.w) * static_cast<uint64_t>(t.h);
    result.samples = static_cast<uint64_t>(task.sampleCount) * result.pixels;
    result.rays = rays.load();
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace pf
