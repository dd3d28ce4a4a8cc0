#include "render/pilot.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "scene/scene.h"

namespace pf {

namespace {

constexpr uint64_t kPilotSeedTag = 0x9170bULL;
constexpr uint64_t kStrataStream = 0x57a7aULL;

}  // namespace

uint64_t pilotSeed(uint64_t jobSeed) { return hashCombine(jobSeed, kPilotSeedTag); }

SeedingResult runPilot(const Scene &scene, const SeedingConfig &config, uint64_t jobSeed, uint64_t samples, bool keep) {
    const auto start = std::chrono::steady_clock::now();
    const uint64_t rays0 = Scene::threadRayCount();
    const Film &film = scene.sensor().film();
    const uint64_t pixels = static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
    const double perSample = static_cast<double>(pixels) / static_cast<double>(samples);
    const uint64_t seed = pilotSeed(jobSeed);
    SeedingResult result;
    PCG32 strata(seed, kStrataStream);
    for (uint64_t j = 0; j < samples; ++j) {
        // Stratum j of the pixels, [j, j + 1) * pixels / samples, a uniform position in it.
        const double u = (static_cast<double>(j) + strata.nextDouble()) * perSample;
        const uint64_t pixel = filmPixel(film, std::min(pixels - 1, static_cast<uint64_t>(u)));
        seedSample(scene, config, seed, pixel, j, perSample, keep, result);
    }
    result.samples = samples;
    result.rays = Scene::threadRayCount() - rays0;
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace pf
