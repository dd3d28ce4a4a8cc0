// A pilot for the dtheta of medium vertices in the manifold perturbation's classification (ALGORITHMS.md §6.6-6.7,
// [TR A1]): a medium vertex joins a chain with probability 1 - P_nonspec(theta_q(g), dtheta), where dtheta is the
// angle by which a perturbation typically turns what the vertex scatters. Jakob does not fix dtheta but measures
// it in a pilot run ([TR §7, A1]); the integrators' default is the surfaces' `manifoldGlossyAngle` (1 degree).
//
// The measurement: short chains with the integrator's mutations (λ and classification as configured) start on
// the luminance pilot's paths (integrators/pilot_chains.h); after every accepted manifold perturbation that keeps
// the path's length, each medium vertex whose scattering angle acos(ω_in · ω_out) changed contributes that change
// (vertices held in a chain keep their offset, hence their angle, and count for nothing). dtheta is the median
// change, not Jakob's mean: the changes are heavy-tailed, and their tail does not depend on λ (a medium x_b takes
// a new free-flight distance, which turns its neighbours' angles by up to tens of degrees). On glass-egg (16²,
// g = 0.8) the median is 2.6° at λ = 10, 1.0° at λ = 50 and 0.39° at λ = 300, the mean 6.1°, 4.0° and 4.0°. Like λ =
// "auto", the value is frozen before any chain of the job runs: detailed balance holds for every fixed dtheta (the
// classification enters T at the source state, path/manifold_perturbation.h), so the pilot changes which strategies are
// sampled, not what the chains converge to. Deterministic for a pilot seed.
#pragma once
#include <vector>

#include "integrators/mlt.h"
#include "render/seeding.h"

namespace pf {

struct MediumAnglePilot {
    double angle = 0;      // dtheta in radians; the integrator's manifoldMediumAngle when nothing was measured
    uint64_t changes = 0;  // medium vertices whose scattering angle a perturbation changed (the median's sample)
};

// dtheta measured on `pool` (records that regenerate with `pilotSeed`) with the jump size `lambda` (0: the
// integrator's); the integrator's own dtheta when the pool carries no energy, the integrator has no manifold
// perturbation, or no medium vertex changed.
MediumAnglePilot pilotMediumAngle(const Scene &scene, const PathSpaceIntegrator &integrator, uint64_t pilotSeed,
                                  const std::vector<SeedCandidate> &pool, double lambda = 0);

}  // namespace pf
