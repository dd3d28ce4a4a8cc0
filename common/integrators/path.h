// The unidirectional path tracer: `volpath` (with participating media) and `path` (Mitsuba's surface-only
// path tracer: the same estimator with media ignored, so index-matched boundaries are plain pass-through), and
// `sms`: `path` with a caustic connection strategy (caustic_connection.h) at its non-specular vertices.
#pragma once
#include <memory>

#include "integrators/caustic_connection.h"
#include "integrators/integrator.h"

namespace pf {

class PathTracer final : public SamplingIntegrator {
public:
    PathTracer(const Properties &props, bool media, std::shared_ptr<const CausticConnection> caustics = nullptr);
    Spectrum Li(const Scene &scene, Sampler &sampler, const Ray &ray) const override;
    void checkScene(const Scene &scene) const override;
    Bitmap render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const override;
    std::string name() const override { return caustics_ ? "sms" : media_ ? "volpath" : "path"; }

private:
    int maxDepth_, rrDepth_;
    bool strictNormals_, hideEmitters_;
    bool media_;  // false: `path`, which ignores media as Mitsuba's does
    std::shared_ptr<const CausticConnection> caustics_;
};

// The direct component of the Markov-chain integrators (`directSamples`: the paths of at most two segments,
// which their chains leave out): `volpath` with maxDepth 2, or the chain integrator's maxDepth if that is
// 1. Mitsuba 0.6 renders this component with its `direct` integrator, or `volpath` of depth 2 in scenes with
// media (libbidir's renderDirectComponent). A BDPT of depth 2 rendered it here before: its light tracing adds
// nothing at that depth but splats, and it took five times as long per sample (issue 17).
std::unique_ptr<SamplingIntegrator> makeDirectComponent(const SourceLocation &loc, int64_t maxDepth);

}  // namespace pf
