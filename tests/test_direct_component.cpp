// The direct component of the Markov-chain integrators (`directSamples`: the paths of at most two segments,
// which their chains leave out): volpath of depth 2 (integrators/path.h, makeDirectComponent), run on
// low-discrepancy numbers whatever the scene's sampler (render/chain_job.h, runDirectTask), as Mitsuba 0.6
// renders it.
#include <gtest/gtest.h>

#include <vector>

#include "render/chain.h"
#include "render/chain_job.h"
#include "support/agreement.h"

namespace pf {
namespace {

using test::blockStats;
using test::expectAgreement;
using test::loadSharedScene;

// A chain integrator of `type` with integer parameters `ints`.
std::unique_ptr<Integrator> chainIntegrator(const std::string &type,
                                            const std::vector<std::pair<std::string, int64_t>> &ints = {}) {
    Properties props(ObjectKind::Integrator, type, {});
    for (const auto &[name, value] : ints) props.set(name, Properties::Type::Integer, value, {});
    return createIntegrator(type, props, true);
}

const SamplingIntegrator &directOf(const Integrator &integrator) {
    const auto *direct = dynamic_cast<const ChainIntegrator &>(integrator).directIntegrator();
    if (!direct) throw std::logic_error(integrator.name() + " has no direct component");
    return *direct;
}

TEST(DirectComponent, IsVolpathOfAtMostTwoSegments) {
    for (const std::string type : {"pssmlt", "mmlt", "mlt", "erpt"})
        EXPECT_EQ(directOf(*chainIntegrator(type)).name(), "volpath") << type;
    // directSamples = 0 or -1: no component, so no integrator for it.
    for (const int64_t n : {0, -1})
        EXPECT_EQ(
            dynamic_cast<const ChainIntegrator &>(*chainIntegrator("mlt", {{"directSamples", n}})).directIntegrator(),
            nullptr);
}

// Unbiased, and exactly the paths of at most two segments: block means agree with BDPT of maxDepth 2 (every
// strategy, light tracing included) within their standard errors over 32 seeds (support/agreement.h), whatever
// the chains' maxDepth above 1 (a component of depth 3 fails by 100 standard errors); with maxDepth 1 both keep
// the emitters seen directly.
TEST(DirectComponent, AgreesWithBDPTOfTheSameDepth) {
    auto scene = loadSharedScene("cornell-box", 32);
    // The chain integrator's maxDepth (-1: unbounded) and the depth of its direct component.
    for (const auto &[chainDepth, depth] : {std::pair<int64_t, int64_t>{-1, 2}, {5, 2}, {1, 1}}) {
        Properties props(ObjectKind::Integrator, "bdpt", {});
        props.set("maxDepth", Properties::Type::Integer, depth, {});
        const auto bdpt = createIntegrator("bdpt", props, true);
        const auto mlt = chainIntegrator("mlt", {{"maxDepth", chainDepth}});
        expectAgreement(blockStats(*scene, *bdpt, 8, 32, 4), blockStats(*scene, directOf(*mlt), 8, 32, 16),
                        "direct component of mlt with maxDepth " + std::to_string(chainDepth));
    }
}

// The scene's sampler does not reach the direct component: the same task gives the same bits under an
// `independent` and an `ldsampler` sampler.
TEST(DirectComponent, DrawsStratifiedNumbersWhateverTheScenesSampler) {
    const auto withSampler = [](const std::string &type) {
        return loadSharedScene("cornell-box", 32, {{R"(<sampler type="sobol" >)", "<sampler type=\"" + type + "\">"}});
    };
    auto independent = withSampler("independent"), ld = withSampler("ldsampler");
    const auto pssmlt = chainIntegrator("pssmlt");
    const auto &chains = dynamic_cast<const ChainIntegrator &>(*pssmlt);
    const ImageTask task{3, 5};
    const ImageTaskResult a = runDirectTask(*independent, chains, 11, task, 2);
    const ImageTaskResult b = runDirectTask(*ld, chains, 11, task, 2);
    const auto sums = [](const ImageTaskResult &r) {
        return std::vector<double>(r.block.sumData().begin(), r.block.sumData().end());
    };
    EXPECT_EQ(sums(a), sums(b));
    // The same integrator and seed on the scene's own numbers: an image of another sequence.
    const ImageTaskResult own = runImageTask(*independent, directOf(*pssmlt), 11, task, 2);
    EXPECT_NE(sums(a), sums(own));
}

}  // namespace
}  // namespace pf
