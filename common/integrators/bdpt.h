// Bidirectional path tracing (`bdpt`) on the path-space layer ([TH A4]; ALGORITHMS.md §0, §1.4; Veach
// 1997 ch. 10). Parameters as in Mitsuba 0.6: maxDepth (edges plus index-matched crossings, path.h; -1 = unbounded),
// rrDepth, lightImage (evaluate the strategies that land on other pixels: t = 1 light tracing and t = 0
// lens hits), sampleDirect (the s = 1 and t = 1 strategies sample their endpoint from the other vertex).
// pathfarm adds `heuristic` ("power", the default, or "balance") and `strategyImages` (a directory that
// receives one EXR of MIS-weighted contributions per strategy, s<s>_t<t>.exr, for debugging).
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "integrators/integrator.h"
#include "path/mis.h"

namespace pf {

// One strategy's share of a pixel sample.
struct StrategySample {
    int s = 0, t = 0;
    int depth = 0;                     // Mitsuba's depth of the path: s + t - 1 plus its crossings (path.h)
    Vec2 raster;                       // where it lands on the film
    double weight = 0;                 // its MIS weight
    Spectrum value;                    // weight * f / p
    const JoinedPath *path = nullptr;  // the path, valid during the visit
};
using StrategyVisitor = std::function<void(const StrategySample &)>;
using Strategy = std::pair<int, int>;  // (s, t)

// A BDPT path in compact form: with the render's seed, the pixel and the sample index regenerate it
// exactly (ALGORITHMS.md §2.4-2.5: seeding hands chains these instead of whole paths).
struct PathRecord {
    uint64_t pixel = 0;  // film pixel index (y * film width + x, crop window included)
    uint64_t sampleIndex = 0;
    int s = 0, t = 0;
};

struct StrategyImage {
    Strategy strategy;
    Bitmap image;
};

class BDPT final : public SamplingIntegrator {
public:
    explicit BDPT(const Properties &props);

    // A pixel sample: the two walks, then every strategy; t >= 2 returns, t <= 1 splats.
    Spectrum sample(const Scene &scene, Sampler &sampler, const Vec2 &raster, SplatList &splats) const override;
    // The strategies that keep the pixel (t >= 2) of a sample through the ray's raster position. Light
    // tracing lands on other pixels and is left out, so images are rendered with sample().
    Spectrum Li(const Scene &scene, Sampler &sampler, const Ray &ray) const override;
    // Renders, and writes the per-strategy images when `strategyImages` is set.
    Bitmap render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const override;
    std::string name() const override { return "bdpt"; }

    // Every strategy of the pixel sample at `raster`, or only `only`; the random numbers drawn are the
    // same either way: the sensor walk, the emitter walk, then two numbers per direct connection
    // (s = 1 for each sensor vertex, then t = 1 for each emitter vertex). Paths of a depth below minDepth
    // are not visited, and not even built where no edge can cross a pass-through surface (the Markov
    // chains leave the direct component's paths to it: connections whose result they dropped were a fifth
    // of a PSSMLT mutation's work; issue 17).
    void evaluate(const Scene &scene, Sampler &sampler, const Vec2 &raster, const StrategyVisitor &visit,
                  std::optional<Strategy> only = {}, int minDepth = 0) const;
    // Regenerates the path of a record from the render's seed (as the render loop draws the sample) and
    // visits it; false if that strategy carries nothing for this sample.
    bool regenerate(const Scene &scene, uint64_t seed, const PathRecord &record, const StrategyVisitor &visit) const;
    // One image per strategy (s + t <= maxDepth + 1) of the MIS-weighted contributions, rendered with the
    // same samples as the full image, so that they sum to it. Needs a finite maxDepth.
    std::vector<StrategyImage> renderStrategyImages(const Scene &scene, const RenderOptions &opt) const;

    const MISOptions &misOptions() const { return mis_; }

private:
    int maxDepth_ = -1, rrDepth_ = 5;
    MISOptions mis_;
    std::string strategyImages_;
    std::optional<Strategy> only_;  // renders of a single strategy (renderStrategyImages)
};

}  // namespace pf
