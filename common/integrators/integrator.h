// Integrators turn a scene into an image. Image-space methods (path tracing now; volpath and BDPT
// later) derive from SamplingIntegrator and only implement Li; the tiling, passes, time budget,
// threading and deterministic merging live in render_loop.cpp, in one place.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/sampler.h"
#include "core/spectrum.h"
#include "image/bitmap.h"
#include "mcmc/metropolis.h"
#include "scene/properties.h"

namespace pf {

class Scene;

// The budget vocabulary shared by every integrator (issue 5 extends its meaning to chains):
// spp = samples per pixel; timeLimit > 0 = wall-clock budget spent in whole passes.
struct RenderOptions {
    int64_t spp = 0;       // 0 = the scene's sampleCount
    double timeLimit = 0;  // seconds; > 0 overrides spp
    // Markov-chain integrators: > 0 renders exactly this many passes of a time budget's plan, the
    // deterministic twin of a `timeLimit` render (or farm job) that ran that many passes; overrides both.
    int64_t passes = 0;
    uint64_t seed = 0;
    int threads = 0;        // 0 = all cores
    bool progress = false;  // draw a progress bar on stderr
    // Called after every pass with the pass count and the image so far (live preview, checkpoints).
    std::function<void(int64_t samplesPerPixel, const Bitmap &image)> onPass;
};

struct RenderStats {
    double seconds = 0;  // wall time of rendering (scene loading excluded)
    int64_t samplesPerPixel = 0;
    // Pixels that took one sample more than samplesPerPixel: a time budget's last, partial pass (image
    // integrators; mergeCoveredPixels).
    int64_t partialPassPixels = 0;
    uint64_t samples = 0;  // camera samples (pixel samples) taken
    uint64_t rays = 0;     // intersect + occluded queries
    // Markov-chain renders: transitions per mutation type and the chains' further statistics.
    MutationCounts counts;
    ChainCounters counters;
};

class Integrator {
public:
    virtual ~Integrator() = default;
    virtual Bitmap render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const = 0;
    virtual std::string name() const = 0;
    // What this integrator asks of the scene beyond its own parameters (e.g. sms's caustic flags), checked
    // where the job is set up (makeIntegrator), so that the farm refuses a job the embedded render refuses.
    // Throws SceneError.
    virtual void checkScene(const Scene &) const {}
};

// Contributions that land on other pixels than the one being sampled (light tracing, BDPT's t = 1
// strategies): raster position and value. They are added to the image unfiltered, in a fixed order.
struct Splat {
    Vec2 raster;
    Spectrum value;
};
using SplatList = std::vector<Splat>;

class SamplingIntegrator : public Integrator {
public:
    // Radiance arriving along `ray` (a primary ray through the film), estimated with `sampler`.
    virtual Spectrum Li(const Scene &scene, Sampler &sampler, const Ray &ray) const = 0;
    // One pixel sample at continuous raster position `raster`: returns the value for that position and
    // may append splats. The default draws a camera ray (aperture sample from `sampler`) and calls Li;
    // bidirectional integrators override it and build the camera subpath themselves.
    virtual Spectrum sample(const Scene &scene, Sampler &sampler, const Vec2 &raster, SplatList &splats) const;
    Bitmap render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const override;
};

// Creates the integrator `type` ("path", ...) from `props`. With `strict` a parameter it does not use is
// an error; without, unused parameters are left for the caller to check (makeIntegrator warns about
// them). Throws SceneError for unknown types or bad parameters.
std::unique_ptr<Integrator> createIntegrator(const std::string &type, const Properties &props, bool strict);
// Names accepted by createIntegrator.
std::string integratorNames();

}  // namespace pf
