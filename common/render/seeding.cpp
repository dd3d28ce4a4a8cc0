#include "render/seeding.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "render/pilot.h"
#include "scene/scene.h"

namespace pf {

namespace {

// Pixels per seeding task: enough BDPT samples that a task's overhead is negligible, few enough that the
// farm can spread seeding over its workers: at most 4096, and small films get at least 16 tasks of at least
// 256 pixels (at 64² one task took mlt's whole seeding, 1.9 s of a 10 s budget, on one of two cores).
constexpr uint64_t kMaxPixelsPerSeedingTask = 4096, kMinPixelsPerSeedingTask = 256, kMinSeedingTasks = 16;

// Sparse seeding's pick: the crop index of the pixel that stands for the run of `runLength` pixels from crop
// index `runStart` (uniform over the run, a pure function of the job seed and the run).
uint64_t seedPixelOfRun(uint64_t seed, uint64_t runStart, uint64_t runLength) {
    if (runLength <= 1) return runStart;
    // A stream no render draws from (sample index 2^64 - 1), so the choice is independent of the samples.
    IndependentSampler sampler(seed, runStart, ~uint64_t{0});
    return runStart + std::min(runLength - 1, static_cast<uint64_t>(sampler.next1D() * static_cast<double>(runLength)));
}

}  // namespace

uint64_t filmPixel(const Film &film, uint64_t cropIndex) {
    const uint64_t w = static_cast<uint64_t>(film.cropWidth());
    return (film.cropY() + cropIndex / w) * static_cast<uint64_t>(film.width()) + film.cropX() + cropIndex % w;
}

Vec2 samplePixel(const Film &film, uint64_t pixel, Sampler &sampler) {
    const uint64_t width = static_cast<uint64_t>(film.width());
    const Vec2 corner(static_cast<double>(pixel % width) - film.cropX(),
                      static_cast<double>(pixel / width) - film.cropY());
    return corner + sampler.next2D();
}

std::vector<SeedingTask> seedingTasks(const Scene &scene) {
    const Film &film = scene.sensor().film();
    const uint64_t pixels = static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
    const uint64_t perTask = std::clamp((pixels + kMinSeedingTasks - 1) / kMinSeedingTasks, kMinPixelsPerSeedingTask,
                                        kMaxPixelsPerSeedingTask);
    std::vector<SeedingTask> tasks;
    for (uint64_t first = 0; first < pixels; first += perTask)
        tasks.push_back({first, std::min(perTask, pixels - first)});
    return tasks;
}

void forEachSeedStrategy(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel,
                         uint64_t sampleIndex, double scale,
                         const std::function<void(const StrategySample &, double)> &fn) {
    IndependentSampler sampler(seed, pixel, sampleIndex);
    const Vec2 raster = samplePixel(scene.sensor().film(), pixel, sampler);
    config.bdpt->evaluate(
        scene, sampler, raster,
        [&](const StrategySample &x) {
            const double weight = x.value.luminance() * scale;
            if (weight > 0 && std::isfinite(weight)) fn(x, weight);
        },
        {}, config.minDepth);
}

void seedSample(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel, uint64_t sampleIndex,
                double scale, bool keep, SeedingResult &result) {
    forEachSeedStrategy(scene, config, seed, pixel, sampleIndex, scale, [&](const StrategySample &x, double weight) {
        if (keep)
            result.candidates.push_back({{pixel, sampleIndex, x.s, x.t},
                                         weight,
                                         result.firstStage.enabled() ? result.firstStage.cell(x.raster) : 0});
        // Per s + t - 1 (MMLT's chains keep s + t; crossings do not change it).
        const size_t depth = static_cast<size_t>(x.s + x.t - 1);
        if (result.depthLuminance.size() <= depth) result.depthLuminance.resize(depth + 1, 0.0);
        result.depthLuminance[depth] += weight;
    });
}

void spreadLuminanceSamples(SeedingConfig &config, const Film &film, int64_t luminanceSamples) {
    const int64_t pixels = static_cast<int64_t>(film.cropWidth()) * film.cropHeight();
    const int64_t samples = std::max<int64_t>(1, luminanceSamples);
    config.samplesPerPixel = std::max<int64_t>(1, (samples + pixels - 1) / pixels);
    config.pixelStride = samples < pixels ? static_cast<uint64_t>(pixels / samples) : 1;
}

SeedingResult runSeedingTask(const Scene &scene, const SeedingConfig &config, uint64_t seed, const SeedingTask &task) {
    if (task.pilotSamples > 0) return runPilot(scene, config, seed, task.pilotSamples);
    const auto start = std::chrono::steady_clock::now();
    const uint64_t rays0 = Scene::threadRayCount();
    const Film &film = scene.sensor().film();
    const uint64_t end = task.firstPixel + task.pixelCount, stride = std::max<uint64_t>(1, config.pixelStride);
    const double perSample = 1.0 / static_cast<double>(config.samplesPerPixel);
    SeedingResult result;
    // Two-stage MLT's first stage covers every pixel whatever the seeding's stride: a cell without samples
    // would hold no luminance.
    if (config.firstStageReduction > 0) {
        result.firstStage = FirstStageImage::zero(film, config.firstStageReduction);
        for (uint64_t i = task.firstPixel; i < end; ++i)
            for (int64_t k = 0; k < config.samplesPerPixel; ++k)
                firstStageSample(scene, config, seed, filmPixel(film, i), static_cast<uint64_t>(k), perSample, result);
    }
    // Runs are cut at the task's ends, so a task's candidates lie in its own pixels, in order (the master
    // checks that of every seeding result), and the split of the image into runs is the same on every machine.
    uint64_t runs = 0;
    for (uint64_t run = task.firstPixel; run < end; run += stride, ++runs) {
        const uint64_t length = std::min(stride, end - run);
        const uint64_t pixel = filmPixel(film, seedPixelOfRun(seed, run, length));
        for (int64_t k = 0; k < config.samplesPerPixel; ++k)
            seedSample(scene, config, seed, pixel, static_cast<uint64_t>(k), perSample * static_cast<double>(length),
                       true, result);
    }
    result.samples = runs * static_cast<uint64_t>(config.samplesPerPixel);
    result.rays = Scene::threadRayCount() - rays0;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace pf
