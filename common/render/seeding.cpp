#include "render/seeding.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "render/pilot.h"
#include "scene/scene.h"

namespace pf {

namespace {

// Pixels per seeding task: enough BDPT samples that a task's overhead is negligible, few enough that the
// farm can spread seeding over its workers.
constexpr uint64_t kPixelsPerSeedingTask = 4096;

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
    std::vector<SeedingTask> tasks;
    for (uint64_t first = 0; first < pixels; first += kPixelsPerSeedingTask)
        tasks.push_back({first, std::min(kPixelsPerSeedingTask, pixels - first)});
    return tasks;
}

void forEachSeedStrategy(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel,
                         uint64_t sampleIndex, double scale,
                         const std::function<void(const StrategySample &, double)> &fn) {
    IndependentSampler sampler(seed, pixel, sampleIndex);
    const Vec2 raster = samplePixel(scene.sensor().film(), pixel, sampler);
    config.bdpt->evaluate(scene, sampler, raster, [&](const StrategySample &x) {
        const double weight = x.value.luminance() * scale;
        if (x.depth >= config.minDepth && weight > 0 && std::isfinite(weight)) fn(x, weight);
    });
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

SeedingResult runSeedingTask(const Scene &scene, const SeedingConfig &config, uint64_t seed, const SeedingTask &task) {
    if (task.pilotSamples > 0) return runPilot(scene, config, seed, task.pilotSamples);
    const auto start = std::chrono::steady_clock::now();
    const uint64_t rays0 = Scene::threadRayCount();
    const Film &film = scene.sensor().film();
    const double perSample = 1.0 / static_cast<double>(config.samplesPerPixel);
    SeedingResult result;
    if (config.firstStageReduction > 0) result.firstStage = FirstStageImage::zero(film, config.firstStageReduction);
    for (uint64_t i = task.firstPixel; i < task.firstPixel + task.pixelCount; ++i)
        for (int64_t k = 0; k < config.samplesPerPixel; ++k) {
            seedSample(scene, config, seed, filmPixel(film, i), static_cast<uint64_t>(k), perSample, true, result);
            if (result.firstStage.enabled())
                firstStageSample(scene, config, seed, filmPixel(film, i), static_cast<uint64_t>(k), perSample, result);
        }
    result.samples = task.pixelCount * static_cast<uint64_t>(config.samplesPerPixel);
    result.rays = Scene::threadRayCount() - rays0;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace pf
