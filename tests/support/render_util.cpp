#include "support/render_util.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace pf::test {

std::string tempDir(const std::string &name) {
    // Per process: CTest runs the tests of one executable in parallel processes, which must not share files.
    const auto dir = std::filesystem::path(PATHFARM_BINARY_DIR) / "test-tmp" / (name + "." + std::to_string(getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

std::string writeFile(const std::string &dir, const std::string &name, const std::string &contents) {
    const auto path = std::filesystem::path(dir) / name;
    std::ofstream(path) << contents;
    return path.string();
}

RenderOutput renderXml(const std::string &xml, const std::string &integrator, int64_t spp, uint64_t seed, int threads) {
    static int counter = 0;
    const std::string dir = tempDir("render-" + std::to_string(counter++));
    auto scene = loadScene(writeFile(dir, "scene.xml", xml));
    const Properties &fileProps = scene->integratorProperties();
    auto integ = createIntegrator(integrator, fileProps, fileProps.pluginName() == integrator);
    RenderOptions opt;
    opt.spp = spp;
    opt.seed = seed;
    opt.threads = threads;
    RenderOutput out;
    out.image = integ->render(*scene, opt, out.stats);
    return out;
}

MeanCI regionMean(const Bitmap &img, int x0, int y0, int x1, int y1, int channel) {
    double sum = 0, sum2 = 0;
    size_t n = 0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const Spectrum s = img.get(x, y);
            const double v = channel < 0 ? s.luminance() : s[channel];
            sum += v;
            sum2 += v * v;
            ++n;
        }
    MeanCI r;
    r.n = n;
    r.mean = sum / n;
    const double var = std::max(0.0, sum2 / n - r.mean * r.mean) * n / std::max<size_t>(1, n - 1);
    r.stderr_ = std::sqrt(var / n);
    return r;
}

}  // namespace pf::test
