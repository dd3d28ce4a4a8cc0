// The portal perturbation at equal time (Otsu, Hanika & Dachsbacher §5; ALGORITHMS.md §7.2): bdpt, mlt with
// the paper's "MLT" mixture (bidirectional mutation and lens perturbation, 0.5 each) and mlt with the
// paper's mixture with portals (bidirectional 0.5, lens 0.25, portal 0.25), on scenes with portals.
//
//   bench_portal [--res N] [--times S1,S2,..] [--ref-spp N] [--threads N] [--runs K] [--out DIR] [scene.xml ..]
//
// Per scene (default scenes/portal-box and scenes/portal-toy) at N x N (default 64): a BDPT reference with
// ref-spp samples per pixel (default 8192), then for each budget (default 30 and 120 seconds) K runs (default
// 1) of each method on `threads` threads (default: all cores): seconds, budget reached (samples or mutations
// per pixel), relMSE (ε = 1e-2) over all pixels and without the worst 0.1% (fireflies), and for the chains
// mutations per second and the acceptance per mutation type. --out writes the reference and each first image
// as EXR. Prints figures only; it never passes or fails.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.h"
#include "image/bitmap.h"
#include "integrators/integrator.h"

namespace {

struct Method {
    std::string label, type;
    std::vector<std::pair<std::string, std::string>> params;
};

// The paper's two mixtures (§5): global and local mutations with equal probability.
const std::vector<std::pair<std::string, std::string>> kPaperMLT = {
    {"lensSubpathMutation", "false"}, {"causticPerturbation", "false"}, {"multiChainPerturbation", "false"}};

std::vector<Method> methods() {
    auto portal = kPaperMLT;
    portal.emplace_back("portalPerturbation", "true");
    return {{"bdpt", "bdpt", {}}, {"mlt", "mlt", kPaperMLT}, {"mlt+portal", "mlt", portal}};
}

std::unique_ptr<pf::Integrator> makeIntegrator(const pf::Scene &scene, const Method &m) {
    pf::Properties props(pf::ObjectKind::Integrator, m.type, {});
    const pf::Properties &file = scene.integratorProperties();
    if (file.has("maxDepth")) props.set("maxDepth", pf::Properties::Type::Integer, file.getInt("maxDepth"), {});
    for (const auto &[name, value] : m.params) props.set(name, pf::Properties::Type::Boolean, value == "true", {});
    return pf::createIntegrator(m.type, props, true);
}

}  // namespace

int main(int argc, char **argv) {
    int res = 64, refSpp = 8192, runs = 1;
    int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    std::vector<double> times = {30, 120};
    std::vector<std::string> scenes;
    std::string out;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const bool value = i + 1 < argc;
        if (a == "--res" && value) {
            res = std::stoi(argv[++i]);
        } else if (a == "--ref-spp" && value) {
            refSpp = std::stoi(argv[++i]);
        } else if (a == "--threads" && value) {
            threads = std::stoi(argv[++i]);
        } else if (a == "--runs" && value) {
            runs = std::stoi(argv[++i]);
        } else if (a == "--out" && value) {
            out = argv[++i];
        } else if (a == "--times" && value) {
            times.clear();
            std::stringstream list(argv[++i]);
            for (std::string t; std::getline(list, t, ',');) times.push_back(std::stod(t));
        } else {
            scenes.push_back(a);
        }
    }
    if (scenes.empty()) scenes = {"scenes/portal-box/scene.xml", "scenes/portal-toy/scene.xml"};
    for (const std::string &path : scenes) {
        const auto scene = bench::loadWithSampleCount(path, 16, res, "bench_portal");
        std::printf("%s, %d x %d, %d threads\n", path.c_str(), res, res, threads);
        pf::RenderStats refStats;
        const pf::Bitmap reference =
            bench::renderWith(*scene, *makeIntegrator(*scene, methods()[0]), refSpp, 0, 1000, threads, refStats);
        std::printf("reference: bdpt, %d spp, %.1f s\n", refSpp, refStats.seconds);
        const std::string stem =
            out.empty() ? "" : out + "/" + std::filesystem::path(path).parent_path().filename().string();
        if (!out.empty()) pf::writeEXR(stem + "-reference.exr", reference);
        std::printf("%-11s %6s %4s %8s %9s %11s %15s %12s  acceptance\n", "", "budget", "run", "seconds", "spp/mpp",
                    "relMSE", "w/o worst 0.1%", "mutations/s");
        for (const double seconds : times)
            for (const Method &m : methods()) {
                const auto integrator = makeIntegrator(*scene, m);
                for (int run = 0; run < runs; ++run) {
                    pf::RenderStats stats;
                    const pf::Bitmap image = bench::renderWith(*scene, *integrator, 0, seconds,
                                                               static_cast<uint64_t>(run + 1), threads, stats);
                    const bench::RelativeError e = bench::relativeError(image, reference);
                    uint64_t mutations = 0;
                    std::string acceptance;
                    for (const pf::MutationCount &c : stats.counts) {
                        mutations += c.proposed;
                        if (c.name == "none" || c.proposed == 0) continue;
                        char buf[64];
                        std::snprintf(buf, sizeof buf, " %s %.1f%%", c.name.c_str(),
                                      100.0 * static_cast<double>(c.accepted) / static_cast<double>(c.proposed));
                        acceptance += buf;
                    }
                    std::printf("%-11s %5.0fs %4d %8.1f %9lld %11.4g %15.4g %12.4g %s\n", m.label.c_str(), seconds, run,
                                stats.seconds, static_cast<long long>(stats.samplesPerPixel), e.all, e.trimmed,
                                mutations / std::max(1e-9, stats.seconds), acceptance.c_str());
                    if (run == 0 && !out.empty())
                        pf::writeEXR(stem + "-" + m.label + "-" + std::to_string(int(seconds)) + "s.exr", image);
                }
            }
    }
    return 0;
}
