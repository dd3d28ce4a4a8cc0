// Helpers of the Markov-chain tests (test_seeding, test_chain_task, test_pssmlt_*, test_long_pssmlt): the
// shared scenes at a small resolution with a box reconstruction filter (chains splat into the pixel a path
// lands in, so a BDPT reference needs the same one-pixel footprint), and block means of images rendered
// with independent seeds, whose seed-to-seed spread is the standard error of each block mean whatever
// the correlations within one render (ALGORITHMS.md §9.1: MCMC error estimates from independent runs).
#pragma once
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "scene/scene.h"
#include "support/render_util.h"
#include "support/seed_stats.h"

namespace pf::test {

// scenes/<name> at res x res with a box filter and an `independent` sampler. The directory is per process: CTest
// runs the cases of one executable as concurrent processes.
inline std::unique_ptr<Scene> loadChainTestScene(const std::string &name, int res) {
    namespace fs = std::filesystem;
    const fs::path src = fs::path(PATHFARM_SOURCE_DIR) / "scenes" / name;
    const std::string dir = tempDir("mcmc-scene-" + name + "-" + std::to_string(getpid()));
    for (const auto &entry : fs::directory_iterator(src))
        if (entry.path().filename() != "scene.xml")
            fs::create_symlink(entry.path(), fs::path(dir) / entry.path().filename());
    std::ifstream in(src / "scene.xml");
    std::stringstream xml;
    xml << in.rdbuf();
    // Markov chains and their seeding draw independent numbers whatever the file asks (core/ld_sampler.h); with
    // `independent` the scene's `bdpt` render draws the same samples as the seeding (test_seeding).
    const std::string boxed =
        std::regex_replace(xml.str(), std::regex(R"(<rfilter type="[a-z]+"\s*/>)"), R"(<rfilter type="box"/>)");
    auto scene = loadScene(writeFile(
        dir, "scene.xml",
        std::regex_replace(boxed, std::regex(R"(<sampler type="[a-z]+"\s*>)"), R"(<sampler type="independent">)")));
    scene->resizeFilm(res, res);
    return scene;
}

// Creates `type` with the scene's maxDepth (the parameter the scenes' path integrators share with every
// other integrator) and `params`.
inline std::unique_ptr<Integrator> makeTestIntegrator(const Scene &scene, const std::string &type,
                                                      const std::vector<std::pair<std::string, std::string>> &params) {
    Properties props(ObjectKind::Integrator, type, {});
    const Properties &file = scene.integratorProperties();
    if (file.has("maxDepth")) props.set("maxDepth", Properties::Type::Integer, file.getInt("maxDepth"), {});
    for (const auto &[name, value] : params) {
        props.remove(name);
        if (value == "true" || value == "false")
            props.set(name, Properties::Type::Boolean, value == "true", {});
        else if (value.find_first_not_of("0123456789+-.e") != std::string::npos)
            props.set(name, Properties::Type::String, value, {});
        else if (value.find_first_of(".e") != std::string::npos)
            props.set(name, Properties::Type::Float, std::stod(value), {});
        else
            props.set(name, Properties::Type::Integer, static_cast<int64_t>(std::stoll(value)), {});
    }
    return createIntegrator(type, props, true);
}

// `type` (with the scene's maxDepth) rendered at `spp` with `seed` on two threads.
inline Bitmap renderTestImage(const Scene &scene, const std::string &type, int64_t spp, uint64_t seed) {
    RenderOptions opt;
    opt.spp = spp;
    opt.seed = seed;
    opt.threads = 2;
    RenderStats stats;
    return makeTestIntegrator(scene, type, {})->render(scene, opt, stats);
}

// Means and standard errors of kxk-pixel block means (per channel), and last of the whole image's
// luminance, over renders with `seeds` independent seeds.
struct BlockStats {
    std::vector<double> mean, stderr_;
};

// The same over images that `render(seed)` returns, for renders that are not Integrator::render's.
inline BlockStats blockStatsOf(const Scene &scene, int block, int seeds, uint64_t seedBase,
                               const std::function<Bitmap(uint64_t seed)> &render) {
    const Film &film = scene.sensor().film();
    const int nx = film.cropWidth() / block, ny = film.cropHeight() / block;
    std::vector<double> sum(static_cast<size_t>(nx * ny * 3 + 1), 0.0), sum2(sum.size(), 0.0);
    const auto add = [&](size_t i, double v) {
        sum[i] += v;
        sum2[i] += v * v;
    };
    for (int k = 0; k < seeds; ++k) {
        const Bitmap img = render(seedBase + 7919 * static_cast<uint64_t>(k + 1));
        for (int by = 0; by < ny; ++by)
            for (int bx = 0; bx < nx; ++bx)
                for (int c = 0; c < 3; ++c)
                    add(static_cast<size_t>((by * nx + bx) * 3 + c),
                        regionMean(img, bx * block, by * block, (bx + 1) * block, (by + 1) * block, c).mean);
        add(sum.size() - 1, regionMean(img, 0, 0, nx * block, ny * block).mean);
    }
    BlockStats r;
    seedMeanAndError(sum, sum2, seeds, r.mean, r.stderr_);
    return r;
}

// Renders with `spp` (or, with timeLimit > 0, under that wall-time budget in seconds).
inline BlockStats blockStats(const Scene &scene, const Integrator &integrator, int block, int seeds, int64_t spp,
                             uint64_t seedBase, int threads = 2, double timeLimit = 0) {
    return blockStatsOf(scene, block, seeds, seedBase, [&](uint64_t seed) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = seed;
        opt.threads = threads;
        opt.timeLimit = timeLimit;
        RenderStats stats;
        return integrator.render(scene, opt, stats);
    });
}

// Block means of `test` agree with `reference` within `sigmas` combined standard errors, and the errors
// are small enough for that to mean something: the median relative error of blocks holding at least 1%
// of the image's mean below `maxMedianError`, and the whole image's luminance below `maxImageError`.
inline void expectBlocksAgree(const BlockStats &reference, const BlockStats &test, double sigmas, double maxMedianError,
                              double maxImageError, const std::string &what) {
    std::vector<double> relative;
    const double imageMean = reference.mean.back();
    for (size_t i = 0; i < reference.mean.size(); ++i) {
        const double se = std::hypot(reference.stderr_[i], test.stderr_[i]);
        const bool whole = i + 1 == reference.mean.size();
        EXPECT_NEAR(test.mean[i], reference.mean[i], sigmas * se)
            << what
            << (whole ? ": whole image" : ": block " + std::to_string(i / 3) + " channel " + std::to_string(i % 3));
        if (!whole && reference.mean[i] > 0.01 * imageMean) relative.push_back(se / reference.mean[i]);
    }
    ASSERT_FALSE(relative.empty());
    std::sort(relative.begin(), relative.end());
    EXPECT_LT(relative[relative.size() / 2], maxMedianError) << what << ": too noisy to compare";
    EXPECT_LT(std::hypot(reference.stderr_.back(), test.stderr_.back()), maxImageError * imageMean)
        << what << ": too noisy to compare";
}

}  // namespace pf::test
