// The seeding phase of Markov-chain rendering (ALGORITHMS.md §2.3-2.4, §5.3; ARCHITECTURE.md "A job, end
// to end", step 2): BDPT over a range of pixels returns compact candidate records instead of paths. A
// record names the render's seed stream position (film pixel, sample index) and the strategy (s, t), so any
// machine regenerates the path exactly (BDPT::regenerate, or a chain's start); its weight is the luminance
// of the strategy's MIS-weighted contribution divided by the samples per pixel, so that the weights of all
// candidates sum to b̂, the BDPT estimate of the total image luminance (§2.3: pixel values are per-pixel
// integrals and b is their sum).
//
// A seeding task is a pure function of (scene, algorithm, job seed, pixel range): pixel p's sample i is
// drawn from IndependentSampler(seed, p, i) exactly as the render loop draws it for a scene whose sampler is
// `independent`, so a retried task returns the same bits, and seeding with seed S takes the same samples as
// `bdpt` rendering such a scene with seed S. Seeding draws independent numbers whatever the scene's sampler
// (as Mitsuba's MLT-type integrators do): a chain replays its seed path from those numbers.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "image/film.h"
#include "integrators/bdpt.h"
#include "render/manifold_tuning.h"
#include "render/two_stage.h"

namespace pf {

struct SeedCandidate {
    PathRecord record;
    double weight = 0;  // luminance of the MIS-weighted contribution / samples per pixel
    uint32_t cell = 0;  // two-stage MLT: the first stage's cell the strategy lands in (render/two_stage.h)
};

// What an algorithm asks of seeding; the same for every task of a job.
struct SeedingConfig {
    const BDPT *bdpt = nullptr;
    int64_t samplesPerPixel = 1;
    // Strategies of paths of smaller depth (edges plus index-matched crossings, path.h) are left out (the
    // component rendered without chains, as with Mitsuba's directSamples); 1 keeps every path.
    int minDepth = 1;
    // Two-stage MLT (render/two_stage.h): the first stage's size reduction; 0: one stage.
    int firstStageReduction = 0;
    // Sparse seeding, for budgets of fewer samples than pixels (Mitsuba's luminanceSamples at 1024²): each
    // seeding task's pixels, row-major, fall into runs of pixelStride (the last one shorter); one pixel drawn
    // uniformly from each run takes the samples and stands for its run, its weights multiplied by the run's
    // length, so b̂ stays unbiased (E[length * L(pick)] = sum of the run's L). 1: every pixel.
    uint64_t pixelStride = 1;
};

// Crop-window pixels [firstPixel, firstPixel + pixelCount) in row-major order; or, when pilotSamples > 0,
// the luminance pilot of burst rendering (render/pilot.h), which takes that many samples over the whole
// crop window and returns no candidates.
struct SeedingTask {
    uint64_t firstPixel = 0;
    uint64_t pixelCount = 0;
    uint64_t pilotSamples = 0;
};

struct SeedingResult {
    std::vector<SeedCandidate> candidates;  // in pixel, sample, strategy order; zero weights left out
    // Sum of the candidates' weights per s + t - 1 (MMLT's chains keep s + t; crossings do not change it).
    std::vector<double> depthLuminance;
    uint64_t samples = 0;        // BDPT samples taken
    ManifoldTuning tuning;       // what the luminance pilot tuned (lambda or manifoldMediumAngle = "auto")
    FirstStageImage firstStage;  // two-stage MLT: the first stage's sums (render/two_stage.h)
    uint64_t rays = 0;
    double seconds = 0;
};

// The fixed split of the crop window into seeding tasks, shared by the embedded renderer and the farm.
std::vector<SeedingTask> seedingTasks(const Scene &scene);

// The task's pixels, or the pilot when it is one.
SeedingResult runSeedingTask(const Scene &scene, const SeedingConfig &config, uint64_t seed, const SeedingTask &task);

// One BDPT seed sample of film pixel `pixel`, drawn from IndependentSampler(seed, pixel, sampleIndex) as the
// render loop draws it from an `independent` sampler: every strategy of a path of at least config.minDepth with a
// positive, finite weight (its luminance times `scale`) is added to result.depthLuminance and, when `keep`, to
// result.candidates. Seeding, the luminance pilot and burst tasks all take their samples through it.
void seedSample(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel, uint64_t sampleIndex,
                double scale, bool keep, SeedingResult &result);
// The strategies seedSample takes from that sample: fn(strategy, weight) for each.
void forEachSeedStrategy(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel,
                         uint64_t sampleIndex, double scale,
                         const std::function<void(const StrategySample &, double)> &fn);

// Sets config's samplesPerPixel and pixelStride to spend at least `luminanceSamples` BDPT samples on the crop
// window: whole samples per pixel, or, below one per pixel, one sample per run of pixels (sparse seeding;
// Mitsuba's default 100000 at 1024² is a tenth of a sample per pixel).
void spreadLuminanceSamples(SeedingConfig &config, const Film &film, int64_t luminanceSamples);
// The film pixel index (PathRecord::pixel) of crop-window pixel `cropIndex`.
uint64_t filmPixel(const Film &film, uint64_t cropIndex);
// The raster position of a pixel sample, drawn from `sampler` as the render loop draws it (two numbers,
// crop-relative raster coordinates): the first step of regenerating a record.
Vec2 samplePixel(const Film &film, uint64_t pixel, Sampler &sampler);

}  // namespace pf
