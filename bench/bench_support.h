// What the integrator benchmarks share: loading a shared scene with another sampleCount (the seeds per
// pixel of ERPT-type bursts, which take their budget from the scene) at a square benchmark resolution, one
// render with a budget, and the equal-time error against a reference (common/image/metrics.h).
#pragma once
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>

#include "image/metrics.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace bench {

// CPU time of the whole process (all threads), in seconds. Rates per CPU second are the figures to compare
// on a machine shared with other work, where wall-clock rates follow the load (issue 17's A/B pairs).
inline double processCpuSeconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The scene at res x res with its sensor's sampleCount set to `spp`, through a rewritten copy of the file
// beside links to the scene's other files (in a per-process temporary directory named after `tag`).
inline std::unique_ptr<pf::Scene> loadWithSampleCount(const std::string &path, int spp, int res,
                                                      const std::string &tag) {
    namespace fs = std::filesystem;
    const fs::path src(path);
    const fs::path dir =
        fs::temp_directory_path() / (tag + "_" + std::to_string(getpid())) / src.parent_path().filename();
    fs::create_directories(dir);
    for (const auto &entry : fs::directory_iterator(src.parent_path()))
        if (entry.path().filename() != src.filename() && !fs::exists(dir / entry.path().filename()))
            fs::create_symlink(fs::absolute(entry.path()), dir / entry.path().filename());
    std::ifstream in(src);
    std::stringstream xml;
    xml << in.rdbuf();
    const std::regex count(R"(<integer name="sampleCount" value="[^"]*"\s*/>)");
    std::ofstream(dir / "scene.xml") << std::regex_replace(
        xml.str(), count, "<integer name=\"sampleCount\" value=\"" + std::to_string(spp) + "\"/>");
    auto scene = pf::loadScene((dir / "scene.xml").string());
    scene->resizeFilm(res, res);
    return scene;
}

// relMSE against `reference` (epsilon 1e-2 in the denominator), over all pixels and without the 0.1% of
// pixels with the largest errors (one bright outlier can hold most of it).
struct RelativeError {
    double all = 0, trimmed = 0;
};
inline RelativeError relativeError(const pf::Bitmap &image, const pf::Bitmap &reference) {
    pf::MetricOptions trim;
    trim.trimFraction = 0.001;
    return {pf::computeMetrics(image, reference).relMse, pf::computeMetrics(image, reference, trim).relMse};
}

// One render of `integrator` with spp samples (or mutations) per pixel, or a time budget of `seconds`.
inline pf::Bitmap renderWith(const pf::Scene &scene, const pf::Integrator &integrator, int64_t spp, double seconds,
                             uint64_t seed, int threads, pf::RenderStats &stats) {
    pf::RenderOptions opt;
    opt.spp = spp;
    opt.timeLimit = seconds;
    opt.seed = seed;
    opt.threads = threads;
    return integrator.render(scene, opt, stats);
}

}  // namespace bench
