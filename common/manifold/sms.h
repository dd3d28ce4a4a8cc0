// Specular manifold sampling of chains of one or two specular vertices (ALGORITHMS.md §7.1, [SMS §4-5]; what the
// reference code gets wrong and this file does not copy: SMS_PORTAL_NOTES.md §1.1, §1.7).
//
// Given a receiver point x_1 (a non-specular surface point) and an emitter point x_3, the specular vertices
// x_2 on a caster shape with C(x_2) = 0 (angle_constraint.h) are the chains x_1 -> x_2 -> x_3 that scatter
// as the caster's event (reflection for conductors, refraction for dielectrics). One *trial* draws a seed
// uniformly by area on the caster, traces x_1 -> seed (the first hit must be the caster), and runs Newton's
// method in the hit's chart: dX = ∂C⁻¹ C, x' = x - β (dp/du dX_0 + dp/dv dX_1), reprojected by tracing a ray
// from x_1 through x' ([SMS §4.2]); a miss or another shape halves β, an accepted step doubles it (up to 1).
// A converged vertex must pass the post-check: x_1 and x_3 on the sides the event requires, and the ideal
// scattered direction about the shading normal equal to the direction to x_3 (this rejects the back-facing
// roots of the half-vector form, [SMS Fig. 7]).
//
// A chain of two vertices x_1 -> x_2 -> x'_2 -> x_3 (the two refractions through a glass sphere, [SMS §5.6]) is
// seeded with the uniform point on the caster for x_2 and the first surface along the ideal specular direction
// out of it for x'_2 ([SMS §4.7]); Newton solves the block-tridiagonal system of both vertices' constraints
// (chainConstraint() in angle_constraint.h, block_tridiagonal.h), reprojects by tracing from x_1 through the
// proposed x_2 and from that hit through the proposed x'_2, and post-checks both events. x_2 must lie on the
// caster, x'_2 on any ideally specular shape.
//
// The sum over all solutions, Σ_k f(x_2,k), is then estimated in one of two ways:
// * unbiased ([SMS §5.1]): a first trial finds x*_k with unknown probability p_k; independent trials of the
//   same (x_1, x_3) then run until one finds the same solution again, and the number of those trials N
//   (the last one included) is geometric with E[N] = 1/p_k, so f(x*_k) N has expectation Σ_k f(x_2,k).
//   Nothing caps N: `trials` is only a runaway guard, and when it fires the estimate keeps the count reached
//   (biased low) and the hit is counted in SmsStatistics::guardHits, never silently 0 (unlike the reference
//   code, SMS_PORTAL_NOTES.md §1.7.1).
// * biased ([SMS §5.2]): `trials` = M trials, and the sum of f over the distinct solutions found. Its
//   expectation is at most the sum; the loss shrinks as M grows.
// Two solutions are the same when their directions from x_1 differ by |cos α - 1| < uniquenessThreshold (the
// first vertex decides the rest of a solved chain).
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "core/sampler.h"
#include "core/spectrum.h"
#include "manifold/angle_constraint.h"

namespace pf {

class Scene;
class Shape;

struct SmsSettings {
    bool biased = false;
    // Biased: M, the trials per estimate; unbiased: the runaway guard on the Bernoulli trials.
    int64_t trials = 1000000;
    SmsConstraint constraint = SmsConstraint::AngleDifference;
    int maxIterations = 20;
    double solverThreshold = 1e-5;
    double uniquenessThreshold = 1e-5;
};

// Counters of a render (updated from all render threads).
struct SmsStatistics {
    std::atomic<uint64_t> estimates{0};      // manifoldSum calls
    std::atomic<uint64_t> solves{0};         // seed-and-solve trials of all kinds
    std::atomic<uint64_t> successes{0};      // trials that ended on a solution passing the post-check
    std::atomic<uint64_t> bernoulli{0};      // unbiased: trials spent re-finding solutions (the counts N)
    std::atomic<uint64_t> solutionsUsed{0};  // unbiased: first solutions that had a nonzero f (with a count N)
    std::atomic<uint64_t> guardHits{0};      // unbiased: counts stopped by the runaway guard
    std::atomic<uint64_t> maxTrials{0};      // unbiased: the largest count N
    void reset();
    double successRate() const;
    double meanTrials() const;  // mean N per estimated solution (unbiased)
};

// How the caster's surface scatters in SMS: Refraction for dielectrics (a BSDF with a delta transmission
// lobe), Reflection for conductors; None when the shape's BSDF is not ideally specular (only delta
// reflection and/or transmission lobes).
Scattering specularEvent(const Shape &caster);

// A solved chain's specular vertices in order from x_1 (each its.wi faces its predecessor).
using SpecularChain = std::vector<Intersection>;

// One trial for a chain of `vertices` (1 or 2) specular vertices whose first is on `caster`: a seed and Newton's
// method from it. nullopt when the trial fails. x1 is the receiver's intersection.
std::optional<SpecularChain> solveSpecularChain(const Scene &scene, const Intersection &x1, const Vec3 &x3,
                                                const Shape &caster, int vertices, const SmsSettings &settings,
                                                Sampler &sampler);
// The one-vertex trial: the solution x_2 (its.wi faces x_1).
std::optional<Intersection> solveSpecularVertex(const Scene &scene, const Intersection &x1, const Vec3 &x3,
                                                const Shape &caster, const SmsSettings &settings, Sampler &sampler);

// The generalized geometry term of the solved chain x_1 -> x_2 (-> x'_2) -> x_3 divided by the geometric cosine at x_1:
// the solid angle at x_1 per unit area at x_3 (per unit intensity for a point x_3, a FixedPosition vertex),
// through the caster's constraint Jacobian (generalized_geometry.h). nullopt on a singular chain.
std::optional<double> specularChainGeometry(const Intersection &x1, const SpecularChain &chain,
                                            const ManifoldVertex &x3);

// The SMS estimate of Σ_k f(chain_k) over the solutions of `vertices` vertices whose first is on `caster` (see
// above). f gets the solution and returns its contribution (visibility included, if wanted).
Spectrum manifoldSum(const Scene &scene, const Intersection &x1, const Vec3 &x3, const Shape &caster, int vertices,
                     const SmsSettings &settings, Sampler &sampler, SmsStatistics &stats,
                     const std::function<Spectrum(const SpecularChain &chain)> &f);

}  // namespace pf
