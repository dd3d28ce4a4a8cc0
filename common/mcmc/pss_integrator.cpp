#include "mcmc/pss_integrator.h"

#include <cmath>

#include "integrators/path.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The BDPT that Psi and the seeding run: every strategy, light tracing included, since a chain's splats land
// wherever the path meets the film.
std::unique_ptr<BDPT> makeBDPT(const SourceLocation &loc, int64_t maxDepth, int64_t rrDepth, bool sampleDirect) {
    Properties p(ObjectKind::Integrator, "bdpt", loc);
    p.set("maxDepth", Properties::Type::Integer, maxDepth, loc);
    p.set("rrDepth", Properties::Type::Integer, rrDepth, loc);
    p.set("sampleDirect", Properties::Type::Boolean, sampleDirect, loc);
    p.set("lightImage", Properties::Type::Boolean, true, loc);
    return std::make_unique<BDPT>(p);
}

}  // namespace

PrimarySampleIntegrator::PrimarySampleIntegrator(const Properties &props) {
    const int64_t maxDepth = props.getInt("maxDepth", -1), rrDepth = props.getInt("rrDepth", 5);
    directSamples_ = props.getInt("directSamples", 16);
    luminanceSamples_ = props.getInt("luminanceSamples", 100000);
    options_.largeStepProbability = props.getFloat("pLarge", 0.3);
    kelemenWeights_ = props.getBool("kelemenStyleWeights", true);
    const bool sampleDirect = props.getBool("directSampling", true);
    options_.sizes.low = props.getFloat("mutationSizeLow", 1.0 / 1024.0);
    options_.sizes.high = props.getFloat("mutationSizeHigh", 1.0 / 64.0);
    firstStageReduction_ = readTwoStage(props);
    if (maxDepth < -1 || maxDepth == 0) props.fail("maxDepth", "must be -1 (unbounded) or at least 1");
    if (rrDepth < 1) props.fail("rrDepth", "must be at least 1");
    if (directSamples_ < -1) props.fail("directSamples", "must be -1 (no separate direct component) or at least 0");
    if (luminanceSamples_ < 1) props.fail("luminanceSamples", "must be at least 1");
    if (!(options_.largeStepProbability >= 0 && options_.largeStepProbability <= 1))
        props.fail("pLarge", "must lie in [0, 1]");
    if (!(options_.sizes.low > 0 && options_.sizes.low < options_.sizes.high && options_.sizes.high < 1))
        props.fail("mutationSizeLow", "the small-step sizes must satisfy 0 < mutationSizeLow < mutationSizeHigh < 1");

    const SourceLocation &loc = props.location();
    bdpt_ = makeBDPT(loc, maxDepth, rrDepth, sampleDirect);
    if (directSamples_ > 0) direct_ = makeDirectComponent(loc, maxDepth);
}

SeedingConfig PrimarySampleIntegrator::seeding(const Scene &scene, int64_t) const {
    SeedingConfig config{bdpt_.get(), 1, minDepth(), firstStageReduction_};
    spreadLuminanceSamples(config, scene.sensor().film(), luminanceSamples_);
    return config;
}

PrimarySampleIntegrator::StartedChain PrimarySampleIntegrator::startChain(const Scene &scene, uint64_t jobSeed,
                                                                          const ChainTask &task, const ChainSeed &seed,
                                                                          double scale, PCG32 &rng,
                                                                          ImageBlock &film) const {
    // The seed's own stream: the raster position first, then the numbers BDPT draws, which become the
    // coordinates of the start state that follow the prefix (ALGORITHMS.md §2.4: the chain starts on the
    // resampled candidate itself).
    IndependentSampler source(jobSeed, seed.record.pixel, seed.record.sampleIndex);
    const Vec2 raster = samplePixel(scene.sensor().film(), seed.record.pixel, source);
    ChainSetup s = setup(scene, task, seed, raster, rng);
    StartedChain started{std::make_unique<PrimarySampleChain>(std::move(s.psi), options_, film, scale,
                                                              task.firstStage.enabled() ? &task.firstStage : nullptr),
                         {}};
    started.chain->start(s.prefix, source);
    // Kelemen's c is the integral of pi over the primary sample space; the raster coordinates spread a
    // sample over the whole film, so it is the image's luminance divided by the pixel count (§2.3).
    const Film &f = scene.sensor().film();
    const double pixels = static_cast<double>(f.cropWidth()) * f.cropHeight();
    if (kelemenWeights_) started.kelemen = KelemenWeights{options_.largeStepProbability, s.normalization / pixels};
    return started;
}

void PrimarySampleIntegrator::runChain(const Scene &scene, uint64_t jobSeed, const ChainTask &task,
                                       const ChainSeed &seed, double scale, PCG32 &rng, ImageBlock &film,
                                       MutationCounts &counts, ChainCounters &) const {
    const StartedChain s = startChain(scene, jobSeed, task, seed, scale, rng, film);
    runMetropolis(*s.chain, task.mutations, rng, s.kelemen ? &*s.kelemen : nullptr, counts);
}

}  // namespace pf
