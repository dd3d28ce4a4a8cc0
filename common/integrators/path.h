// The unidirectional path tracer (`path`).
#pragma once
#include "integrators/integrator.h"
#include "scene/intersection.h"

namespace pf {

class PathTracer final : public SamplingIntegrator {
public:
    explicit PathTracer(const Properties &props);
    Spectrum Li(const Scene &scene, Sampler &sampler, const Ray &ray) const override;
    std::string name() const override { return "path"; }

private:
    Spectrum emitted(const Scene &scene, const Ray &ray, const Intersection &its, const Vec3 &ref, double bsdfPdf,
                     bool deltaSample) const;
    int maxDepth_, rrDepth_;
    bool strictNormals_, hideEmitters_;
};

}  // namespace pf
