// Two-stage MLT (Mitsuba 0.6's `twoStage` on `mlt` and `pssmlt`; Veach 1997 §11.5 "importance sampling
// the image", Kelemen et al. 2002 §5): long chains spend their mutations in proportion to the luminance
// a pixel receives, so bright regions get most of them and dark ones stay noisy. A first stage estimates
// a low-resolution image I of the chains' component; the second stage's chains then target
// pi'(x) = L(x) / I(cell of x), which spends mutations uniformly per cell, and the result is re-weighted
// by the normalization of pi' instead of pi. For any fixed, positive I the estimate keeps its
// properties: the seeding candidates of pi' are those of pi with weights w / I(cell) (they are importance
// weights of pi' as the w are of pi), b̂' = sum of those weights estimates the integral of pi', and each
// deposit f / pi' times b̂' / M is the one-stage estimator for the target pi' (ALGORITHMS.md §2.3-2.4).
//
// I must not depend on the pool it re-weights (b̂' / b' would then not average to 1), so the first stage
// takes its own samples: beside each of its seed samples a seeding task takes one BDPT sample of an
// independent stream and adds every strategy of the chains' depths to the cell it lands in (per pixel of
// the cell). The merged sums of all seeding tasks are I, floored at a fraction of their mean so that a
// cell the first stage saw dark still has pi' > 0 wherever L > 0 (ergodicity) and cannot hold a chain
// with an unbounded weight. Mitsuba's first stage is a nested MLT render at the reduced resolution;
// pathfarm's is this BDPT estimate, which is independent of the pool by construction and reaches the
// farm's tasks with the seeding results (the master merges it like b̂ and hands it to every chain task).
#pragma once
#include <cstdint>
#include <vector>

#include "core/vector.h"

namespace pf {

class Film;
class Properties;
struct SeedingConfig;
struct SeedingResult;
class Scene;

// Mitsuba's default firstStageSizeReduction: the first stage's image is 16 times smaller in x and y.
constexpr int kFirstStageSizeReduction = 16;

// The first stage's image over the crop window, `reduction` pixels per cell in x and y (0: one stage).
struct FirstStageImage {
    int reduction = 0, width = 0, height = 0;
    std::vector<double> luminance;  // per cell, row-major: luminance per pixel of the cell

    // A zero image of `film`'s crop window.
    static FirstStageImage zero(const Film &film, int reduction);
    bool enabled() const { return reduction > 0; }
    // The cell of a crop-relative raster position (clamped to the window).
    uint32_t cell(const Vec2 &raster) const;
    // The factor that turns L(x) into pi'(x) for a path landing at `raster`: 1 / I, or 1 with one stage.
    double targetFactor(const Vec2 &raster) const { return enabled() ? 1.0 / luminance[cell(raster)] : 1.0; }
};

// Mitsuba's twoStage and firstStageSizeReduction of `mlt` and `pssmlt`: the reduction, 0 for one stage.
int readTwoStage(const Properties &props);

// The first stage's sample beside seed sample (pixel, sampleIndex) of a seeding task: an independent
// BDPT sample whose strategies add luminance * `scale` / (pixels of the cell) to result.firstStage.
void firstStageSample(const Scene &scene, const SeedingConfig &config, uint64_t seed, uint64_t pixel,
                      uint64_t sampleIndex, double scale, SeedingResult &result);

// I from the merged sums: each cell floored at kFirstStageFloor times the cells' mean (all 1 if the
// first stage saw nothing, which leaves one-stage MLT).
constexpr double kFirstStageFloor = 0.01;
FirstStageImage firstStageImportance(FirstStageImage sums);

}  // namespace pf
