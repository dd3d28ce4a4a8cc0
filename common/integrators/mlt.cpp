#include "integrators/mlt.h"

#include <algorithm>
#include <cmath>

#include "integrators/path.h"
#include "path/bidirectional_mutation.h"
#include "path/caustic_perturbation.h"
#include "path/lens_perturbation.h"
#include "path/lens_subpath_mutation.h"
#include "path/manifold_perturbation.h"
#include "path/medium_distance_perturbation.h"
#include "path/multichain_perturbation.h"
#include "path/portal_perturbation.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The parameter that enables each mutation type, in MutationType order.
constexpr const char *kMutationParameters[kMutationTypes] = {
    "bidirectionalMutation",  "lensSubpathMutation",  "lensPerturbation",           "causticPerturbation",
    "multiChainPerturbation", "manifoldPerturbation", "mediumDistancePerturbation", "portalPerturbation"};

// The BDPT that seeds the chains: every strategy, light tracing included, since a path lands wherever it meets
// the film.
std::unique_ptr<BDPT> makeBDPT(const SourceLocation &loc, int64_t maxDepth, int64_t rrDepth) {
    Properties p(ObjectKind::Integrator, "bdpt", loc);
    p.set("maxDepth", Properties::Type::Integer, maxDepth, loc);
    p.set("rrDepth", Properties::Type::Integer, rrDepth, loc);
    return std::make_unique<BDPT>(p);
}

}  // namespace

const char *mutationParameter(MutationType type) { return kMutationParameters[static_cast<int>(type)]; }

PathSpaceIntegrator::PathSpaceIntegrator(const Properties &props, const std::vector<MutationType> &defaults) {
    const int64_t maxDepth = props.getInt("maxDepth", -1), rrDepth = props.getInt("rrDepth", 10);
    directSamples_ = props.getInt("directSamples", 16);
    for (int k = 0; k < kMutationTypes; ++k) {
        const auto type = static_cast<MutationType>(k);
        // The medium-distance perturbation belongs to manifold exploration (its chains hold medium distances):
        // on by default wherever the manifold perturbation is (it applies to paths with medium vertices only).
        const bool byDefault = type == MutationType::MediumDistance
                                   ? usesManifoldPerturbation()
                                   : std::find(defaults.begin(), defaults.end(), type) != defaults.end();
        if (props.getBool(mutationParameter(type), byDefault)) types_.push_back(type);
    }
    // Mitsuba reads the manifold perturbation's jump size as probFactor, defaulting to lambda; either may
    // be "auto" here (tuned by the luminance pilot of erpt and mept).
    for (const char *name : {"lambda", "probFactor"}) {
        if (!props.has(name)) continue;
        lambdaAuto_ = props.type(name) == Properties::Type::String;
        if (!lambdaAuto_) {
            lambda_ = props.getFloat(name);
        } else if (props.getString(name) != "auto") {
            props.fail(name, "must be a positive number or \"auto\"");
        }
    }
    if (!(lambda_ > 0) || !std::isfinite(lambda_)) props.fail("lambda", "must be positive");
    const double glossyAngle = props.getFloat("manifoldGlossyAngle", 1.0);
    if (!(glossyAngle >= 0 && glossyAngle < 180)) props.fail("manifoldGlossyAngle", "must lie in [0, 180) degrees");
    glossyAngle_ = glossyAngle * kPi / 180;
    // "auto": measured by the luminance pilot of erpt and mept; until then (and where it measures nothing) the
    // surfaces' angle.
    mediumAngleAuto_ =
        props.has("manifoldMediumAngle") && props.type("manifoldMediumAngle") == Properties::Type::String;
    if (mediumAngleAuto_ && props.getString("manifoldMediumAngle") != "auto")
        props.fail("manifoldMediumAngle", "must be an angle in degrees or \"auto\"");
    const double mediumAngle = mediumAngleAuto_ ? glossyAngle : props.getFloat("manifoldMediumAngle", glossyAngle);
    if (!(mediumAngle >= 0 && mediumAngle < 180)) props.fail("manifoldMediumAngle", "must lie in [0, 180) degrees");
    mediumAngle_ = mediumAngle * kPi / 180;
    mediumChains_ = props.getBool("mediumChains", true);
    // The portal perturbation's angles: the paper's 2^-8 and 2^-4 radians (Otsu et al., §5).
    portalR1_ = props.getFloat("portalR1", 1.0 / 256);
    portalR2_ = props.getFloat("portalR2", 1.0 / 16);
    if (!(portalR1_ > 0 && portalR1_ < portalR2_ && portalR2_ <= kPi / 2))
        props.fail("portalR2", "the portal angles need 0 < portalR1 < portalR2 <= pi / 2");
    if (maxDepth < -1 || maxDepth == 0) props.fail("maxDepth", "must be -1 (unbounded) or at least 1");
    if (rrDepth < 1) props.fail("rrDepth", "must be at least 1");
    if (directSamples_ < -1) props.fail("directSamples", "must be -1 (no separate direct component) or at least 0");
    if (types_.empty()) props.fail("bidirectionalMutation", "at least one mutation or perturbation must be enabled");
    maxDepth_ = static_cast<int>(maxDepth);
    bdpt_ = makeBDPT(props.location(), maxDepth, rrDepth);
    if (directSamples_ > 0) direct_ = makeDirectComponent(props.location(), maxDepth);
}

SeedingConfig PathSpaceIntegrator::seedingWith(int64_t samplesPerPixel) const {
    return {bdpt_.get(), samplesPerPixel, minVertices() - 1};
}

bool PathSpaceIntegrator::usesManifoldPerturbation() const {
    return std::find(types_.begin(), types_.end(), MutationType::Manifold) != types_.end();
}

MutationSet PathSpaceIntegrator::mutations(const Scene &scene, const ManifoldTuning &tuned) const {
    const PerturbationScale scale(scene);
    MutationSet set;
    // With portals, the portal perturbation's paper (Otsu et al., §5) gives the global mutation the
    // probability of all local ones together: bidirectional 0.5, lens and portal 0.25 each.
    const bool portalMix =
        !scene.portals().empty() && std::find(types_.begin(), types_.end(), MutationType::Portal) != types_.end();
    const double bidirectionalWeight = portalMix ? std::max(1.0, static_cast<double>(types_.size() - 1)) : 1.0;
    for (const MutationType type : types_) switch (type) {
            case MutationType::Bidirectional:
                set.add(std::make_unique<BidirectionalMutation>(minVertices(), maxVertices()), bidirectionalWeight);
                break;
            case MutationType::LensSubpath:
                set.add(std::make_unique<LensSubpathMutation>());
                break;
            case MutationType::Lens:
                set.add(std::make_unique<LensPerturbation>(scale));
                break;
            case MutationType::Caustic:
                set.add(std::make_unique<CausticPerturbation>(scale));
                break;
            case MutationType::MultiChain:
                set.add(std::make_unique<MultiChainPerturbation>(scale));
                break;
            case MutationType::Manifold:
                set.add(std::make_unique<ManifoldPerturbation>(
                    scene, tuned.lambda > 0 ? tuned.lambda : lambda_, glossyAngle_, mediumChains_,
                    tuned.mediumAngle > 0 ? tuned.mediumAngle : mediumAngle_));
                break;
            case MutationType::MediumDistance:
                set.add(std::make_unique<MediumDistancePerturbation>());
                break;
            case MutationType::Portal:
                set.add(std::make_unique<PortalPerturbation>(scene, portalR1_, portalR2_));
                break;
        }
    return set;
}

void PathSpaceIntegrator::runChain(const Scene &scene, uint64_t jobSeed, const ChainTask &task, const ChainSeed &seed,
                                   double scale, PCG32 &rng, ImageBlock &film, MutationCounts &counts,
                                   ChainCounters &counters) const {
    // The chain starts on the resampled candidate itself (ALGORITHMS.md §2.4), regenerated from its record.
    MutablePath start;
    bdpt_->regenerate(scene, jobSeed, seed.record, [&](const StrategySample &x) { start = MutablePath(*x.path); });
    const MutationSet set = mutations(scene, task.tuning);
    PathChain chain(scene, set, minVertices(), maxVertices(), film, scale,
                    task.firstStage.enabled() ? &task.firstStage : nullptr);
    // A candidate carries energy, so its path does; pi = 0 could only come from round-off in re-evaluating
    // a Dirac vertex from the other side, and such a start is left out rather than divided by.
    if (start.length() > 0 && chain.start(start) > 0) runMetropolis(chain, task.mutations, rng, nullptr, counts);
    for (size_t k = 0; k < set.size(); ++k) set[k].addCounters(counters);
    // What the pilot tuned is reported with the chains' statistics (and in the image's metadata), dtheta in degrees.
    if (task.tuning.lambda > 0) addCounters(counters, {{"lambda", task.tuning.lambda, ChainCounter::Merge::Max}});
    if (task.tuning.mediumAngle > 0)
        addCounters(counters, {{"mediumAngle", task.tuning.mediumAngle * 180 / kPi, ChainCounter::Merge::Max}});
}

namespace {

// MLT's mutations by default, and MEMLT's ([TR §8]; ALGORITHMS.md §5.4): the bidirectional mutation for
// ergodicity and the manifold perturbation in place of Veach's perturbations.
std::vector<MutationType> mltDefaults(bool manifoldExploration) {
    if (manifoldExploration) return {MutationType::Bidirectional, MutationType::Manifold};
    return {MutationType::Bidirectional, MutationType::LensSubpath, MutationType::Lens, MutationType::Caustic,
            MutationType::MultiChain};
}

}  // namespace

MLT::MLT(const Properties &props, bool manifoldExploration)
    : PathSpaceIntegrator(props, mltDefaults(manifoldExploration)), manifoldExploration_(manifoldExploration) {
    luminanceSamples_ = props.getInt("luminanceSamples", 100000);
    if (luminanceSamples_ < 1) props.fail("luminanceSamples", "must be at least 1");
    if (lambdaAuto()) props.fail("lambda", "\"auto\" is for erpt and mept (their luminance pilot tunes it)");
    if (mediumAngleAuto())
        props.fail("manifoldMediumAngle", "\"auto\" is for erpt and mept (their luminance pilot measures it)");
    firstStageReduction_ = readTwoStage(props);
}

// Veach's mutations are cheap: on cornell-box at 1024² a task of 2^16 took 0.12 s on one core, while its film
// (most of the image's tiles) took 51 ms to encode on a worker and 27 ms to decode and merge on the master, and
// a farm of one 2-thread worker made 15 mutations per pixel in 30 s where the embedded render made 24 (issue 17).
// So mlt's tasks take up to 2^18 mutations, still a fraction of a second to a few seconds on one core, the
// least a time budget can stop at. The manifold perturbation costs many times more per step: memlt, and mlt
// with it, keep the default.
uint64_t MLT::taskMutations(const Scene &scene) const {
    return usesManifoldPerturbation() ? ChainIntegrator::taskMutations(scene)
                                      : chainTaskMutations(scene, uint64_t{1} << 18);
}

SeedingConfig MLT::seeding(const Scene &scene, int64_t) const {
    SeedingConfig config = seedingWith(1);
    spreadLuminanceSamples(config, scene.sensor().film(), luminanceSamples_);
    config.firstStageReduction = firstStageReduction_;
    return config;
}

}  // namespace pf
