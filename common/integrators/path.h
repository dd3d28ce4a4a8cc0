// The unidirectional path tracer: `volpath` (with participating media) and `path` (Mitsuba's surface-only
// path tracer: the same estimator with media ignored, so index-matched boundaries are plain pass-through).
#pragma once
#include "integrators/integrator.h"

namespace pf {

class PathTracer final : public SamplingIntegrator {
public:
    PathTracer(const Properties &props, bool media);
    Spectrum Li(const Scene &scene, Sampler &sampler, const Ray &ray) const override;
    std::string name() const override { return media_ ? "volpath" : "path"; }

private:
    int maxDepth_, rrDepth_;
    bool strictNormals_, hideEmitters_;
    bool media_;  // false: `path`, which ignores media as Mitsuba's does
};

}  // namespace pf
