// lambda = "auto" for erpt and mept: the manifold perturbation's jump size λ chosen by the luminance pilot
// (render/pilot.h) instead of by hand. Jakob & Marschner report 72-78% acceptance at their hand-tuned λ
// ([TR §8, Table 1]; ALGORITHMS.md §6); λ sets the peak of the perturbation's kernel at λ² times uniform
// (path/manifold_perturbation.h), so a larger λ means smaller steps and more acceptance.
//
// The pilot's paths, which come from a random stream of their own, start short chains with every enabled
// mutation; after each batch of steps, log λ moves by a Robbins-Monro step γ_n (a_n - target) against the
// batch's manifold acceptance a_n (γ_n = n^-0.6), and the result is the mean of log λ over the second half
// of the batches. λ is then frozen for the whole job: adapting during the render's chains would make their
// kernel depend on their own history and bias the image, while a λ fixed from an independent stream is
// just another jump size. Deterministic for a job seed, so every machine renders with the same λ.
#pragma once
#include <vector>

#include "integrators/mlt.h"
#include "render/seeding.h"

namespace pf {

// The manifold perturbation's target acceptance: the middle of the seeds' 72-78%.
constexpr double kLambdaTargetAcceptance = 0.75;

// λ tuned on `pool` (records that regenerate with `pilotSeed`), starting from the integrator's λ; that λ when
// the pool carries no energy or the integrator has no manifold perturbation.
double tuneLambda(const Scene &scene, const PathSpaceIntegrator &integrator, uint64_t pilotSeed,
                  const std::vector<SeedCandidate> &pool);

}  // namespace pf
