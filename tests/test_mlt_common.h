// Helpers of the path-space MCMC tests (test_detailed_balance, test_mlt, test_erpt and their long versions):
// the shared scenes or Veach's swimming pool at a small resolution, with a box reconstruction filter (chains
// splat into the pixel a path lands in, so a BDPT reference needs the same one-pixel footprint) and a chosen
// sampleCount (ERPT's seeds per pixel); ERPT with a single mutation; a render's mutation counts.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include "integrators/mlt.h"
#include "render/normalizer.h"
#include "scene/scene.h"
#include "support/chain_util.h"
#include "support/render_util.h"
#include "test_pssmlt_common.h"

namespace pf::test {

// Veach's swimming pool (Veach & Guibas 1997): a diffuse floor under a water surface, lit from above.
// Seen from above ("pool"), its light paths L S D S E cross two specular chains: the multi-chain
// perturbation's case. Seen from under water ("pool-underwater"), the floor shows the caustic L S D E: the
// caustic perturbation's case, through a Dirac refraction.
inline std::string poolScene(const std::string &cameraOrigin) {
    return R"(<scene version="0.6.0">
    <integrator type="path"><integer name="maxDepth" value="6"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="toWorld"><lookat origin=")" +
           cameraOrigin + R"(" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sampleCount" value="4"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="toWorld"><scale x="3" y="3"/><rotate x="1" angle="-90"/><translate y="1"/></transform>
        <bsdf type="dielectric"><float name="intIOR" value="1.33"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="toWorld"><scale x="3" y="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.7, 0.8"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="toWorld"><rotate x="1" angle="90"/><translate y="4"/></transform>
        <emitter type="area"><rgb name="radiance" value="10, 10, 10"/></emitter>
    </shape>
</scene>)";
}

// scenes/<name> (or "pool", "pool-underwater") at res x res with a box filter and `sampleCount` samples per pixel.
inline std::unique_ptr<Scene> loadMLTTestScene(const std::string &name, int res, int sampleCount) {
    namespace fs = std::filesystem;
    const std::string dir =
        tempDir("mlt-scene-" + name + "-" + std::to_string(res) + "-" + std::to_string(sampleCount));
    std::string xml = name == "pool" ? poolScene("0, 4, 3") : poolScene("0.3, 0.8, 0.4");
    // Variants of a shipped scene: "<scene>-analytic" has its sphere meshes replaced by analytic spheres (the
    // same geometry), "<scene>-thinlens" its perspective camera by a thin lens (aperture radius 0.1, focused
    // at 6, for the endpoint position perturbation on the aperture), "<scene>-largelight" (glass-egg) its light 5
    // times as wide, so that BDPT, the reference, finds the light seen through the egg often enough,
    // "<scene>-independent" its sampler replaced by `independent`, "<scene>-ldsampler" by `ldsampler` with
    // dimension 3 (pixel samples from core/ld_sampler.h stratified in the first three 1D and 2D requests) and
    // "<scene>-imagesobol" by `sobol` with layout "image" (core/global_sobol_sampler.h).
    struct Variant {
        std::string suffix, pattern, replacement;
    };
    const std::vector<Variant> variants = {
        {"-analytic", R"(<shape type="obj">\s*<string name="filename" value="models/sphere.obj"\s*/>)",
         R"(<shape type="sphere">)"},
        {"-thinlens", R"(<sensor type="perspective"\s*>)",
         R"(<sensor type="thinlens"><float name="apertureRadius" value="0.1"/><float name="focusDistance" value="6"/>)"},
        {"-largelight", R"(<default name="lightScale" value="0.1"\s*/>)",
         R"(<default name="lightScale" value="0.5"/>)"},
        {"-independent", R"(<sampler type="[a-z]+"\s*>)", R"(<sampler type="independent">)"},
        {"-ldsampler", R"(<sampler type="[a-z]+"\s*>)",
         R"(<sampler type="ldsampler"><integer name="dimension" value="3"/>)"},
        {"-imagesobol", R"(<sampler type="[a-z]+"\s*>)",
         R"(<sampler type="sobol"><string name="layout" value="image"/>)"}};
    std::string base = name;
    const Variant *variant = nullptr;
    for (const Variant &v : variants)
        if (base.size() > v.suffix.size() &&
            base.compare(base.size() - v.suffix.size(), v.suffix.size(), v.suffix) == 0) {
            base.resize(base.size() - v.suffix.size());
            variant = &v;
        }
    if (base.rfind("pool", 0) != 0) {
        const fs::path src = fs::path(PATHFARM_SOURCE_DIR) / "scenes" / base;
        for (const auto &entry : fs::directory_iterator(src))
            if (entry.path().filename() != "scene.xml")
                fs::create_symlink(entry.path(), fs::path(dir) / entry.path().filename());
        std::ifstream in(src / "scene.xml");
        std::stringstream text;
        text << in.rdbuf();
        xml = std::regex_replace(text.str(), std::regex(R"(<rfilter type="[a-z]+"\s*/>)"), R"(<rfilter type="box"/>)");
        if (variant) xml = std::regex_replace(xml, std::regex(variant->pattern), variant->replacement);
    }
    xml = std::regex_replace(xml, std::regex(R"(<integer name="sampleCount" value="\d+"\s*/>)"),
                             "<integer name=\"sampleCount\" value=\"" + std::to_string(sampleCount) + "\"/>");
    auto scene = loadScene(writeFile(dir, "scene.xml", xml));
    scene->resizeFilm(res, res);
    return scene;
}

// ERPT's parameters for using the mutation `type` alone (every path left to the chains).
inline std::vector<std::pair<std::string, std::string>> singleMutation(MutationType type) {
    std::vector<std::pair<std::string, std::string>> params = {{"directSamples", "-1"}};
    for (int k = 0; k < kMutationTypes; ++k)
        params.emplace_back(mutationParameter(static_cast<MutationType>(k)),
                            k == static_cast<int>(type) ? "true" : "false");
    return params;
}

// The same on top of `params` (other parameters of the chains).
inline std::vector<std::pair<std::string, std::string>> singleMutationWith(
    MutationType type, const std::vector<std::pair<std::string, std::string>> &params) {
    auto all = singleMutation(type);
    all.insert(all.end(), params.begin(), params.end());
    return all;
}

// The per-type counts and the further chain counters (the manifold walks) of one render's chain tasks, with
// `spp` the render's budget (seeds per pixel for erpt, mutations per pixel for mlt), seeded with 3.
struct ChainStatistics {
    MutationCounts counts;
    ChainCounters counters;
};
inline ChainStatistics chainStatistics(const Scene &scene, const Integrator &integrator, int64_t spp) {
    const auto &chains = dynamic_cast<const ChainIntegrator &>(integrator);
    const Normalizer normalizer = seedChains(scene, chains, 3);
    ChainStatistics stats;
    for (uint64_t k = 0; k < chains.chainTaskCount(scene, spp); ++k) {
        const ChainResult r = runChainTask(scene, chains, 3, chains.chainTask(scene, normalizer, 3, spp, k));
        addCounts(stats.counts, r.counts);
        addCounters(stats.counters, r.counters);
    }
    return stats;
}

// The per-type counts of one render's chain tasks at the scene's sampleCount.
inline MutationCounts mutationCounts(const Scene &scene, const Integrator &integrator) {
    return chainStatistics(scene, integrator, scene.sensor().sampleCount()).counts;
}

// The longest paths a comparison renders: the scene's maxDepth (0), or `maxDepth` edges.
inline std::vector<std::pair<std::string, std::string>> withMaxDepth(
    std::vector<std::pair<std::string, std::string>> params, int maxDepth) {
    if (maxDepth != 0) params.emplace_back("maxDepth", std::to_string(maxDepth));
    return params;
}

// A BDPT reference: block means over `seeds` renders of `spp` samples per pixel, computed once per
// (scene, resolution, seeds, spp, maxDepth) for all the cases of a test binary.
inline const BlockStats &bdptReference(const std::string &name, const Scene &scene, int block, int seeds, int spp,
                                       int maxDepth, const std::string &type = "bdpt") {
    static std::map<std::string, BlockStats> cache;
    const Film &film = scene.sensor().film();
    const std::string key = type + "/" + name + "/" + std::to_string(film.cropWidth()) + "/" + std::to_string(block) +
                            "/" + std::to_string(seeds) + "/" + std::to_string(spp) + "/" + std::to_string(maxDepth);
    const auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    return cache[key] =
               blockStats(scene, *makeTestIntegrator(scene, type, withMaxDepth({}, maxDepth)), block, seeds, spp, 1);
}

// How a convergence test is run: image size, block size, renders, the reference's samples per pixel, the
// chains' budget (mutations per pixel for mlt, the scene's sampleCount of seeds for erpt), the longest paths
// of both (0: the scene's maxDepth) and the agreement thresholds (in standard errors, and the largest median
// block error and image error that still allow a meaningful comparison).
struct ConvergenceSetup {
    int res = 16, block = 8, seeds = 16, referenceSpp = 64, budget = 32;
    double timeLimit = 0;  // > 0: the chains render under this wall-time budget (seconds) instead
    double sigmas = 4.5, maxMedianError = 0.05, maxImageError = 0.03;
    int maxDepth = 0;
    std::string reference = "bdpt";  // the reference integrator (`volpath` for scenes with media, too)
};

// The set-up of the long suites (label "long"): 32 x 32, 32 independent renders against a 128 spp BDPT
// reference, 49 comparisons per case at 5 standard errors of a Student t with 31 degrees of freedom.
inline ConvergenceSetup longConvergenceSetup(int budget, int maxDepth = 0) {
    ConvergenceSetup s;
    s.res = 32;
    s.seeds = 32;
    s.referenceSpp = 128;
    s.budget = budget;
    s.sigmas = 5;
    s.maxMedianError = 0.04;
    s.maxImageError = 0.02;
    s.maxDepth = maxDepth;
    return s;
}

// The set-up of a comparison under a wall-time budget of `seconds` per render: the renders' lengths differ
// and shrink on a loaded machine (ctest runs two tests at once), so the noise guards are those at which a
// 15% bias still stands out at 4.5 standard errors; the agreement itself is tested as for budgets in samples.
inline ConvergenceSetup timeBudgetSetup(double seconds, int maxDepth = 0) {
    ConvergenceSetup s;
    s.timeLimit = seconds;
    s.maxMedianError = 0.08;
    s.maxImageError = 0.035;
    s.maxDepth = maxDepth;
    return s;
}

// A scene name as a gtest parameter name ('-' is not allowed there).
inline std::string gtestName(std::string name) {
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

// The figures of a comparison, printed by every convergence case for the record: the median relative
// combined standard error of the blocks expectBlocksAgree weighs (those above 1% of the image's mean), the
// whole image's, and the largest |z| = |test - reference| / (combined standard error) over all comparisons.
inline void printAgreement(const BlockStats &reference, const BlockStats &test, const std::string &what) {
    std::vector<double> relative;
    double worst = 0;
    size_t worstIndex = 0;
    for (size_t i = 0; i < reference.mean.size(); ++i) {
        const double se = std::hypot(reference.stderr_[i], test.stderr_[i]);
        const double z = se > 0 ? std::abs(test.mean[i] - reference.mean[i]) / se : 0.0;
        if (z > worst) {
            worst = z;
            worstIndex = i;
        }
        if (i + 1 < reference.mean.size() && reference.mean[i] > 0.01 * reference.mean.back())
            relative.push_back(se / reference.mean[i]);
    }
    std::sort(relative.begin(), relative.end());
    const double image = std::hypot(reference.stderr_.back(), test.stderr_.back()) / reference.mean.back();
    std::printf(
        "%s: %zu comparisons, median block error %.2f%%, image error %.2f%% (image %+.2f%%), worst |z| %.2f (%s)\n",
        what.c_str(), reference.mean.size(), relative.empty() ? 0.0 : 100 * relative[relative.size() / 2], 100 * image,
        100 * (test.mean.back() / reference.mean.back() - 1), worst,
        worstIndex + 1 == reference.mean.size()
            ? "whole image"
            : ("block " + std::to_string(worstIndex / 3) + " channel " + std::to_string(worstIndex % 3)).c_str());
}

// `integrator` (params on top of the scene's maxDepth) on `name` agrees with BDPT.
inline void expectConvergence(const std::string &name, const std::string &type,
                              const std::vector<std::pair<std::string, std::string>> &params, const ConvergenceSetup &s,
                              const std::string &what) {
    const bool bursts = type == "erpt";
    auto scene = loadMLTTestScene(name, s.res, bursts ? s.budget : 4);
    const auto integrator = makeTestIntegrator(*scene, type, withMaxDepth(params, s.maxDepth));
    const BlockStats chains =
        blockStats(*scene, *integrator, s.block, s.seeds, bursts ? 0 : s.budget, 2, 2, s.timeLimit);
    const BlockStats &reference =
        bdptReference(name, *scene, s.block, s.seeds, s.referenceSpp, s.maxDepth, s.reference);
    printAgreement(reference, chains, s.reference == "bdpt" ? what : what + " against " + s.reference);
    expectBlocksAgree(reference, chains, s.sigmas, s.maxMedianError, s.maxImageError, what);
}

// ERPT with the single mutation `type` (and `params`, e.g. numChains) agrees with BDPT, and that mutation is
// accepted often enough to have shown a bias (a mutation that never moves cannot bias anything): in at least
// 2% of its proposals.
inline void expectSingleMutationConvergence(const std::string &name, MutationType type, const ConvergenceSetup &s,
                                            const std::vector<std::pair<std::string, std::string>> &params = {}) {
    const auto all = singleMutationWith(type, params);
    auto scene = loadMLTTestScene(name, s.res, s.budget);
    const auto integrator = makeTestIntegrator(*scene, "erpt", withMaxDepth(all, s.maxDepth));
    for (const MutationCount &count : mutationCounts(*scene, *integrator))
        if (count.name == mutationName(type)) {
            EXPECT_GT(count.accepted, count.proposed / 50) << count.name << " is hardly ever accepted";
        }
    expectConvergence(name, "erpt", all, s, name + " " + mutationName(type));
}

}  // namespace pf::test
