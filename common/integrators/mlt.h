// Veach's path-space Metropolis light transport (`mlt`; Veach & Guibas 1997; Veach 1997 ch. 11;
// ALGORITHMS.md §2, §4): long Markov chains on path space, seeded by BDPT and normalized by its estimate b̂
// of the total image luminance (render/chain.h, render/normalizer.h). A chain's state is a complete path,
// its target the path's luminance, and its transitions Veach's mutations and perturbations (path/*.h):
// the bidirectional mutation gives ergodicity, the lens subpath mutation moves over the image, and the
// lens, caustic and multi-chain perturbations explore the neighbourhood of a path. Mitsuba 0.6 parameter
// names and defaults:
//
//   maxDepth (-1)                  longest path in edges plus index-matched crossings (path.h; -1: unbounded)
//   rrDepth (10)                   Russian roulette of the seeding BDPT (Mitsuba's MLT hard-codes 10)
//   directSamples (16)             samples per pixel of the direct component (paths of at most two edges),
//                                  rendered by volpath without chains; 0 hides it, -1 leaves it to the chains
//   luminanceSamples (100000)      BDPT samples for seeding and b̂, rounded up to whole samples per pixel
//   bidirectionalMutation (true), lensPerturbation (true), causticPerturbation (true),
//   multiChainPerturbation (true)  the mutations in use
//   lensSubpathMutation (true)     Veach's lens subpath mutation (not in Mitsuba 0.6, which dropped it)
//   manifoldPerturbation (false)   manifold exploration's manifold perturbation (path/manifold_perturbation.h)
//   lambda (50)                    the manifold perturbation's jump size (Mitsuba also reads probFactor,
//                                  which takes precedence); erpt and mept also take "auto" (erpt.h)
//   manifoldGlossyAngle (1)        dtheta of the manifold perturbation's glossy classification, in degrees:
//                                  the mean turn of a microfacet normal per perturbation (Mitsuba's starting
//                                  value); 0 leaves every glossy vertex non-specular
//   mediumChains (true)            whether medium vertices may join the manifold perturbation's chains (§6.7),
//                                  classified with manifoldMediumAngle against their phase function's median
//   manifoldMediumAngle (= manifoldGlossyAngle)  dtheta of medium vertices, in degrees (the typical turn of
//                                  a scattering angle per perturbation); erpt and mept also take "auto": their
//                                  luminance pilot measures it (integrators/medium_angle_pilot.h)
//   mediumDistancePerturbation (= manifoldPerturbation)  the medium-distance perturbation
//   twoStage (false)               two-stage MLT (render/two_stage.h): a first stage's low-resolution image
//                                  I steers the chains, whose target becomes L / I
//   firstStageSizeReduction (16)   the first stage's image is this many times smaller in x and y
//   portalPerturbation (false)     the portal perturbation (path/portal_perturbation.h), for scenes with portals
//   portalR1, portalR2 (2^-8, 2^-4)  its range of angles in radians
//
// --spp is mutations per pixel (Mitsuba's sampleCount).
//
// `memlt` (manifold exploration MLT, [TR §8]; ALGORITHMS.md §5.4) is this integrator with the bidirectional
// mutation and the manifold perturbation on by default and Veach's perturbations off; the same parameters
// switch any of them.
#pragma once
#include <memory>
#include <vector>

#include "integrators/bdpt.h"
#include "path/path_chain.h"
#include "render/chain.h"

namespace pf {

// The parameter that enables a mutation type (bidirectionalMutation, lensPerturbation, ...).
const char *mutationParameter(MutationType type);

// What MLT and ERPT share: the BDPT that seeds the chains, the direct component's path tracer, the set of
// mutations, and the chain itself, a PathChain started on a regenerated seeding candidate.
class PathSpaceIntegrator : public ChainIntegrator {
public:
    MutationCounts mutationTypes() const override { return PathChain::mutationTypes(types_); }
    void runChain(const Scene &scene, uint64_t jobSeed, const ChainTask &task, const ChainSeed &seed, double scale,
                  PCG32 &rng, ImageBlock &film, MutationCounts &counts, ChainCounters &counters) const override;
    const SamplingIntegrator *directIntegrator() const override { return direct_.get(); }
    int64_t directSamples() const override { return directSamples_; }

    // The enabled mutations, in mutationTypes() order, with their step sizes for `scene`; the manifold
    // perturbation's jump size and medium dtheta as `tuned` (fields of 0: the integrator's).
    MutationSet mutations(const Scene &scene, const ManifoldTuning &tuned = {}) const;
    // lambda = "auto": the jump size is tuned by the luminance pilot (integrators/erpt.h).
    bool lambdaAuto() const { return lambdaAuto_; }
    double lambda() const { return lambda_; }
    // manifoldMediumAngle = "auto": the luminance pilot measures dtheta of medium vertices (erpt.h).
    bool mediumAngleAuto() const { return mediumAngleAuto_; }
    // dtheta of medium vertices in the manifold perturbation's classification, in radians.
    double mediumAngle() const { return mediumAngle_; }
    bool usesManifoldPerturbation() const;
    const BDPT &bdpt() const { return *bdpt_; }
    // Chains leave paths with fewer vertices to the direct component.
    int minVertices() const { return directSamples_ >= 0 ? 4 : 2; }
    // The longest paths (-1: unbounded).
    int maxVertices() const { return maxDepth_ < 0 ? -1 : maxDepth_ + 1; }

protected:
    // Reads the parameters the two share; `defaults` says which mutations are on unless set.
    PathSpaceIntegrator(const Properties &props, const std::vector<MutationType> &defaults);
    // The seeding with `samplesPerPixel` BDPT samples per pixel.
    SeedingConfig seedingWith(int64_t samplesPerPixel) const;

private:
    std::unique_ptr<BDPT> bdpt_;
    std::unique_ptr<SamplingIntegrator> direct_;  // integrators/path.h: makeDirectComponent
    int maxDepth_ = -1;
    int64_t directSamples_ = 16;
    double lambda_ = 50, glossyAngle_ = 0, mediumAngle_ = 0;
    bool mediumChains_ = true;
    double portalR1_ = 0, portalR2_ = 0;
    bool lambdaAuto_ = false, mediumAngleAuto_ = false;
    std::vector<MutationType> types_;
};

class MLT final : public PathSpaceIntegrator {
public:
    // manifoldExploration: MEMLT's default mutations and name.
    explicit MLT(const Properties &props, bool manifoldExploration = false);
    std::string name() const override { return manifoldExploration_ ? "memlt" : "mlt"; }
    SeedingConfig seeding(const Scene &scene, int64_t spp = 0) const override;
    uint64_t taskMutations(const Scene &scene) const override;

private:
    int64_t luminanceSamples_ = 100000;
    int firstStageReduction_ = 0;
    bool manifoldExploration_ = false;
};

}  // namespace pf
