#include "support/agreement.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "support/render_util.h"
#include "support/seed_stats.h"

namespace pf::test {

namespace fs = std::filesystem;

namespace {

std::string readText(const fs::path &path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace

std::unique_ptr<Scene> loadSharedScene(const std::string &name, int res, const std::vector<Edit> &edits) {
    const fs::path src = fs::path(PATHFARM_SOURCE_DIR) / "scenes" / name;
    const std::string dir = tempDir("bdpt-scene-" + name);
    for (const auto &entry : fs::directory_iterator(src))
        if (entry.path().filename() != "scene.xml")
            fs::create_symlink(entry.path(), fs::path(dir) / entry.path().filename());
    std::string xml = std::regex_replace(readText(src / "scene.xml"), std::regex(R"(<rfilter type="[a-z]+"\s*/>)"),
                                         R"(<rfilter type="box"/>)");
    for (const Edit &e : edits) {
        const size_t at = xml.find(e.from);
        EXPECT_NE(at, std::string::npos) << name << ": no '" << e.from << "' to edit";
        if (at != std::string::npos) xml.replace(at, e.from.size(), e.to);
    }
    auto scene = loadScene(writeFile(dir, "scene.xml", xml));
    if (res > 0) scene->resizeFilm(res, res);
    return scene;
}

BlockStats blockStats(const Scene &scene, const Integrator &integrator, int block, int seeds, int spp) {
    const Film &film = scene.sensor().film();
    const int nx = film.cropWidth() / block, ny = film.cropHeight() / block;
    std::vector<double> sum(static_cast<size_t>(nx * ny * 3 + 1), 0.0), sum2(sum.size(), 0.0);
    for (int k = 0; k < seeds; ++k) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = 7919 * static_cast<uint64_t>(k + 1);
        opt.threads = 1;
        RenderStats stats;
        const Bitmap img = integrator.render(scene, opt, stats);
        for (int by = 0; by < ny; ++by)
            for (int bx = 0; bx < nx; ++bx)
                for (int c = 0; c < 3; ++c) {
                    const double v =
                        regionMean(img, bx * block, by * block, (bx + 1) * block, (by + 1) * block, c).mean;
                    sum[static_cast<size_t>((by * nx + bx) * 3 + c)] += v;
                    sum2[static_cast<size_t>((by * nx + bx) * 3 + c)] += v * v;
                }
        const double v = regionMean(img, 0, 0, nx * block, ny * block).mean;
        sum.back() += v;
        sum2.back() += v * v;
    }
    BlockStats r;
    seedMeanAndError(sum, sum2, seeds, r.mean, r.stderr_);
    return r;
}

void expectAgreement(const BlockStats &a, const BlockStats &b, const std::string &what) {
    std::vector<double> relative;
    const double imageMean = a.mean.back();
    for (size_t i = 0; i < a.mean.size(); ++i) {
        const double se = std::hypot(a.stderr_[i], b.stderr_[i]);
        const bool whole = i + 1 == a.mean.size();
        EXPECT_NEAR(b.mean[i], a.mean[i], 5 * se)
            << what
            << (whole ? ": whole image" : ": block " + std::to_string(i / 3) + " channel " + std::to_string(i % 3));
        if (!whole && a.mean[i] > 0.01 * imageMean) relative.push_back(se / a.mean[i]);
    }
    ASSERT_FALSE(relative.empty());
    std::sort(relative.begin(), relative.end());
    const double median = relative[relative.size() / 2];
    EXPECT_LT(median, 0.03) << what << ": too noisy to compare";
    std::printf("%s: median block standard error %.2f%%, image %.4g vs %.4g +- %.2g\n", what.c_str(), 100 * median,
                b.mean.back(), a.mean.back(), std::hypot(a.stderr_.back(), b.stderr_.back()));
}

}  // namespace pf::test
