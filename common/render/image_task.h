// The seam between renderer and farm for image-space integrators (path, volpath, bdpt): an
// ImageTask renders samples [firstSample, firstSample + sampleCount) of every pixel of the film's crop
// window into an unnormalized ImageBlock. It is a pure function of (scene, integrator, seed, task):
// the embedded renderer and the farm's workers run the same function, and merging task results in
// task order gives the same bits wherever the tasks ran.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/sample_sequence.h"
#include "image/film.h"
#include "integrators/integrator.h"

namespace pf {

struct ImageTask {
    int64_t firstSample = 0;
    int64_t sampleCount = 1;
    // The first `tiles` of the film's tiles only, in their fixed order (an embedded time budget's last,
    // partial pass; see mergeCoveredPixels); -1: all of them, which is what the farm's tasks are.
    int64_t tiles = -1;
};

struct ImageTaskResult {
    ImageBlock block;
    uint64_t samples = 0;  // pixel samples taken
    uint64_t pixels = 0;   // pixels whose samples were taken (fewer than the film's in a partial pass)
    uint64_t rays = 0;
    double seconds = 0;
    // Each tile's rendering time (one thread's), in the film's tile order: what a partial pass of the first tiles
    // costs (timedPartialTiles).
    std::vector<float> tileSeconds = {};
};

// Runs the task on `threads` threads. Tiles are rendered in any order but merged in a fixed order. The pixel
// samples draw the numbers of `sequence`, or of the scene's sampler if it is null.
ImageTaskResult runImageTask(const Scene &scene, const SamplingIntegrator &integrator, uint64_t seed,
                             const ImageTask &task, int threads, const SampleSequence *sequence = nullptr);

// An empty block covering the scene's crop window (what tasks are merged into; Tiles: a chain task's film).
ImageBlock makeFilmBlock(const Scene &scene, BlockStorage storage = BlockStorage::Dense);

// Splits a budget of `spp` samples per pixel of a film (crop window) of `pixels` pixels into the fixed task
// sizes used by both the embedded renderer and the farm (so that their images agree bitwise): the size of
// the task that starts at `firstSample`. Up to 256² pixels: 8 up to sample 128, then growing with the
// samples before it up to 256; larger films scale both bounds down, to 1 and 16 at 1024².
int64_t imageTaskSize(int64_t spp, int64_t firstSample, int64_t pixels);

// The samples per pixel of the next pass of an embedded render under a time budget of `budget` seconds, of
// which `elapsed` are spent, after a pass `last` that took `lastSeconds` (none yet: sampleCount 0); 0 means
// stop. The clock decides whether another whole pass starts, never when one stops, so each pass is sized
// from the pace of the one before: about 1/64 of the budget, growing at most twofold per pass, and never
// more than the time left holds, so that the last pass fills the budget instead of leaving a pass's time
// unused. The first pass is one sample per pixel, and a film whose one sample per pixel takes longer than
// the time left stops there; the render loop then fills the rest with a partial pass (timedPartialTiles).
// A pass has fixed costs: starting threads, clearing and merging a film, and the wait for the last tile; at
// 64² and 1 spp per pass they took 7% of two cores' time.
int64_t timedPassSize(double budget, double elapsed, const ImageTask &last, double lastSeconds);

// The tiles of one sample per pixel that the time left holds at the pace of the pass `last` (which took
// `lastSeconds`), out of `tiles` (never all of them: that would be a whole pass); 0 when not one does. At 1024²,
// one sample per pixel of BDPT takes about 5 s on two cores, and whole passes alone left 4.9 s of a 30 s budget
// unused on cornell-box. With `tileSeconds` (that pass's ImageTaskResult::tileSeconds, one per tile) the first n
// tiles cost their share of the pass, not n / tiles of it: tiles differ (the first 367 of cornell-box's 1024 at
// 1024² cost BDPT 29% more than the average tile, and a farm job sized by the average ended 0.33 s late).
int64_t timedPartialTiles(double budget, double elapsed, const ImageTask &last, double lastSeconds, int64_t tiles,
                          std::span<const float> tileSeconds = {});

// The film's pixels as imageTaskSize counts them.
int64_t filmPixels(const Film &film);

// The tiles a task of the film is rendered in (the unit of a partial pass).
int64_t filmTiles(const Film &film);

// The pixels of the film's first `tiles` tiles (a partial pass's samples).
int64_t tilePixels(const Film &film, int64_t tiles);

// Per crop pixel, row-major: whether a partial pass over the film's first `tiles` tiles covers its whole filter
// footprint, and so gives it one more sample (mergeCoveredPixels).
std::vector<char> partialPassFootprints(const Film &film, int64_t tiles);

// Adds a partial pass (a task over the film's first `tiles` tiles) to `film`, a block of whole passes: the
// weighted sums and weights of the pixels whose every sample could come from those tiles, all of its splats.
// A pixel's value is the ratio of its sums, an average of the samples in the filter's footprint weighted by
// the filter; where the footprint reaches uncovered pixels, that footprint would hold one sample more per pixel
// on one side than on the other, and the average would weight the covered side more. So those pixels, and
// the uncovered ones, keep the whole passes' samples alone, and every pixel's footprint stays evenly sampled.
// Light tracing's splats estimate their image from every light path traced, wherever its camera sample was,
// so they all count, and the film's splat scale becomes pixels / (light paths traced) (Film::develop).
void mergeCoveredPixels(ImageBlock &film, ImageBlock pass, const Film &filmDesc, int64_t tiles);

// The splat scale of a film of `pixels` pixels whose whole passes took `spp` samples per pixel and whose partial
// pass `partialPixels` more: pixels / light paths traced (Film::develop). pixels / (spp pixels) rounds to the same
// double as 1 / spp, so images without a partial pass keep their bits.
double splatScale(int64_t pixels, int64_t spp, int64_t partialPixels);

// How a render's summary says a partial pass covered `share` of the pixels: " + 1 in 71% of pixels" (empty
// without one), for `render`, `submit --wait` and `fetch` alike.
std::string partialPassSummary(double share);

}  // namespace pf
