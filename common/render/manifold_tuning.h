// What the luminance pilot of erpt and mept may tune before a job's chains run: the manifold perturbation's
// jump size λ (lambda = "auto", integrators/lambda_tuning.h) and the dtheta by which its classification decides
// whether a medium vertex joins a chain (manifoldMediumAngle = "auto", integrators/medium_angle_pilot.h).
// Both are measured on paths from a random stream of their own and then frozen: the pilot's seeding result
// carries them to the normalizer, which hands them to every chain task, so that every machine's chains run one
// fixed kernel (detailed balance holds for any fixed λ and dtheta; adapting them during the chains would not).
#pragma once

namespace pf {

struct ManifoldTuning {
    double lambda = 0;       // 0: the integrator's `lambda`
    double mediumAngle = 0;  // radians; 0: the integrator's `manifoldMediumAngle`
    bool operator==(const ManifoldTuning &) const = default;
};

}  // namespace pf
