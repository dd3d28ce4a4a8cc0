// Helpers of the path-space MCMC tests (test_detailed_balance, test_mlt, test_erpt and their long versions):
// the shared scenes or Veach's swimming pool at a small resolution, with a box reconstruction filter (chains
// splat into the pixel a path lands in, so a BDPT reference needs the same one-pixel footprint) and a chosen
// sampleCount (ERPT's seeds per pixel); ERPT with a single mutation; a render's mutation counts.
#pragma once
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
    if (name.rfind("pool", 0) != 0) {
        const fs::path src = fs::path(PATHFARM_SOURCE_DIR) / "scenes" / name;
        for (const auto &entry : fs::directory_iterator(src))
            if (entry.path().filename() != "scene.xml")
                fs::create_symlink(entry.path(), fs::path(dir) / entry.path().filename());
        std::ifstream in(src / "scene.xml");
        std::stringstream text;
        text << in.rdbuf();
        xml = std::regex_replace(text.str(), std::regex(R"(<rfilter type="[a-z]+"\s*/>)"), R"(<rfilter type="box"/>)");
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

// The per-type counts of one render's chain tasks.
inline MutationCounts mutationCounts(const Scene &scene, const Integrator &integrator) {
    const auto &chains = dynamic_cast<const ChainIntegrator &>(integrator);
    const Normalizer normalizer = seedChains(scene, chains, 3);
    MutationCounts counts;
    const int64_t spp = scene.sensor().sampleCount();
    for (uint64_t k = 0; k < chains.chainTaskCount(scene, spp); ++k)
        addCounts(counts, runChainTask(scene, chains, 3, chains.chainTask(scene, normalizer, 3, spp, k)).counts);
    return counts;
}

// A BDPT reference: block means over `seeds` renders of `spp` samples per pixel, computed once per
// (scene, resolution, seeds, spp) for all the cases of a test binary.
inline const BlockStats &bdptReference(const std::string &name, const Scene &scene, int block, int seeds, int spp) {
    static std::map<std::string, BlockStats> cache;
    const Film &film = scene.sensor().film();
    const std::string key = name + "/" + std::to_string(film.cropWidth()) + "/" + std::to_string(block) + "/" +
                            std::to_string(seeds) + "/" + std::to_string(spp);
    const auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    return cache[key] = blockStats(scene, *makeTestIntegrator(scene, "bdpt", {}), block, seeds, spp, 1);
}

// How a convergence test is run: image size, block size, renders, the reference's samples per pixel, the
// chains' budget (mutations per pixel for mlt, the scene's sampleCount of seeds for erpt) and the agreement
// thresholds (in standard errors, and the largest median block error and image error that still allow a
// meaningful comparison).
struct ConvergenceSetup {
    int res = 16, block = 8, seeds = 16, referenceSpp = 64, budget = 32;
    double sigmas = 4.5, maxMedianError = 0.05, maxImageError = 0.03;
};

// `integrator` (params on top of the scene's maxDepth) on `name` agrees with BDPT.
inline void expectConvergence(const std::string &name, const std::string &type,
                              const std::vector<std::pair<std::string, std::string>> &params, const ConvergenceSetup &s,
                              const std::string &what) {
    const bool bursts = type == "erpt";
    auto scene = loadMLTTestScene(name, s.res, bursts ? s.budget : 4);
    const auto integrator = makeTestIntegrator(*scene, type, params);
    const BlockStats chains = blockStats(*scene, *integrator, s.block, s.seeds, bursts ? 0 : s.budget, 2);
    expectBlocksAgree(bdptReference(name, *scene, s.block, s.seeds, s.referenceSpp), chains, s.sigmas, s.maxMedianError,
                      s.maxImageError, what);
}

// ERPT with the single mutation `type` agrees with BDPT, and that mutation is accepted often enough to have
// shown a bias (a mutation that never moves cannot bias anything): in at least 2% of its proposals.
inline void expectSingleMutationConvergence(const std::string &name, MutationType type, const ConvergenceSetup &s) {
    auto scene = loadMLTTestScene(name, s.res, s.budget);
    for (const MutationCount &count : mutationCounts(*scene, *makeTestIntegrator(*scene, "erpt", singleMutation(type))))
        if (count.name == mutationName(type)) {
            EXPECT_GT(count.accepted, count.proposed / 50) << count.name << " is hardly ever accepted";
        }
    expectConvergence(name, "erpt", singleMutation(type), s, name + " " + mutationName(type));
}

}  // namespace pf::test
