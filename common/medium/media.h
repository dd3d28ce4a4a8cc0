// Factories of the participating-medium and phase-function plugins (Mitsuba 0.6 names and parameters),
// listed by mediumPlugins() (scene/medium_plugins.cpp) and phasePlugins() (medium/phase_plugins.cpp),
// and the phase-function helpers shared by the media, the integrators and the manifold code.
#pragma once
#include <memory>

#include "scene/medium.h"
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createHomogeneousMedium(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createIsotropicPhase(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createHGPhase(const Properties &props, const LoadContext &ctx);

// Mitsuba 0.6's default phase function of a medium without a nested <phase>.
std::shared_ptr<PhaseFunction> makeIsotropicPhase();

// Inverse CDF of the Henyey-Greenstein distribution of mu = cos(angle between the propagation
// direction and the scattered direction): the mu with P(cos <= mu) = u. Written without a division by
// g, so it stays accurate as g -> 0 (where it becomes the uniform 2u - 1).
double hgSampleCosine(double g, double u);

// ALGORITHMS.md §6.6 (media) / [TR A1]: the cosine of the q-quantile theta_q of the HG scattering angle,
// measured from the forward direction for g >= 0 and from the backward direction for g < 0 (the formula
// uses |g|). Manifold exploration classifies medium vertices with it; q = 0.5, g = 0.8 gives 0.944.
double hgQuantileCosine(double g, double q);

}  // namespace pf
