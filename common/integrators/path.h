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

}  // namespace pf
