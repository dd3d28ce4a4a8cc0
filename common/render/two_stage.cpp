#include "render/two_stage.h"

#include <algorithm>

#include "render/seeding.h"
#include "scene/properties.h"
#include "scene/scene.h"

namespace pf {

namespace {

// Keeps the first stage's samples apart from the seeding's, which they must not be correlated with.
constexpr uint64_t kFirstStageSeedTag = 0xf125ULL;

}  // namespace

int readTwoStage(const Properties &props) {
    const int64_t reduction = props.getInt("firstStageSizeReduction", kFirstStageSizeReduction);
    if (reduction < 1 || reduction > 1 << 16) props.fail("firstStageSizeReduction", "must lie in [1, 65536]");
    return props.getBool("twoStage", false) ? static_cast<int>(reduction) : 0;
}

FirstStageImage FirstStageImage::zero(const Film &film, int reduction) {
    FirstStageImage image;
    image.reduction = reduction;
    image.width = (film.cropWidth() + reduction - 1) / reduction;
    image.height = (film.cropHeight() + reduction - 1) / reduction;
    image.luminance.assign(static_cast<size_t>(image.width) * static_cast<size_t>(image.height), 0.0);
    return image;
}

uint32_t FirstStageImage::cell(const Vec2 &raster) const {
    const int x = std::clamp(static_cast<int>(raster.x) / reduction, 0, width - 1),
              y = std::clamp(static_cast<int>(raster.y) / reduction, 0, height - 1);
    return static_cast<uint32_t>(y * width + x);
}

void firstStageSample(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel,
                      uint64_t sampleIndex, double scale, SeedingResult &result) {
    const Film &film = scene.sensor().film();
    FirstStageImage &image = result.firstStage;
    forEachSeedStrategy(scene, config, hashCombine(seed, kFirstStageSeedTag), pixel, sampleIndex, scale,
                        [&](const StrategySample &x, double weight) {
                            // Cells at the right and bottom edges may hold fewer pixels than reduction².
                            const uint32_t c = image.cell(x.raster);
                            const int cx = static_cast<int>(c) % image.width, cy = static_cast<int>(c) / image.width;
                            const int w = std::min(film.cropWidth() - cx * image.reduction, image.reduction),
                                      h = std::min(film.cropHeight() - cy * image.reduction, image.reduction);
                            image.luminance[c] += weight / static_cast<double>(w * h);
                        });
}

FirstStageImage firstStageImportance(FirstStageImage sums) {
    double mean = 0;
    for (double l : sums.luminance) mean += l;
    mean /= static_cast<double>(std::max<size_t>(1, sums.luminance.size()));
    for (double &l : sums.luminance) l = mean > 0 ? std::max(l, kFirstStageFloor * mean) : 1.0;
    return sums;
}

}  // namespace pf
