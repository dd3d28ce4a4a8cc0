// The `pathfarm` command line. `pathfarm render SCENE` renders on this machine (the embedded default);
// the farm commands (submit, status, watch, fetch, cancel, workers, health) talk to a farm master;
// `pathfarm diff` measures an image against a reference and `pathfarm compare` runs equal-time
// comparisons of integrators on a farm.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <thread>

#include "compare.h"
#include "core/error.h"
#include "diff.h"
#include "farm/job_setup.h"
#include "farm_commands.h"
#include "image/bitmap.h"
#include "image/film.h"
#include "integrators/integrator.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace {

struct RenderArgs {
    std::string scene, output, integrator;
    int64_t spp = 0;
    double time = 0;
    int64_t passes = 0;
    uint64_t seed = 0;
    int threads = 0;
    std::vector<std::string> defines, params;
    bool quiet = false, strict = false;
};

int runRender(const RenderArgs &a) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    auto scene = pf::loadScene(a.scene, pf::parseNameValues(a.defines, "-D"), a.strict);
    const double loadSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    std::vector<pf::SceneWarning> warnings = scene->warnings();
    auto integrator =
        pf::makeIntegrator(*scene, a.integrator, pf::parseNameValues(a.params, "-P"), a.strict, &warnings);
    // Mitsuba 0.6 logs unused parameters and renders on; so does pathfarm unless --strict made them errors.
    for (const pf::SceneWarning &w : warnings) std::fprintf(stderr, "warning: %s\n", w.str().c_str());

    pf::RenderOptions opt;
    opt.spp = a.spp;
    opt.timeLimit = a.time;
    opt.passes = a.passes;
    opt.seed = a.seed;
    opt.threads = a.threads > 0 ? a.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    opt.progress = !a.quiet;
    pf::RenderStats stats;
    pf::Bitmap image = integrator->render(*scene, opt, stats);

    image.metadata["pathfarm.integrator"] = integrator->name();
    image.metadata["pathfarm.spp"] = std::to_string(stats.samplesPerPixel);
    if (stats.partialPassPixels > 0)
        image.metadata["pathfarm.partialPassPixels"] = std::to_string(stats.partialPassPixels);
    image.metadata["pathfarm.seed"] = std::to_string(a.seed);
    image.metadata["pathfarm.renderSeconds"] = std::to_string(stats.seconds);
    image.metadata["pathfarm.sceneLoadSeconds"] = std::to_string(loadSeconds);
    image.metadata["pathfarm.scene"] = a.scene;
    // What a chain integrator's pilot tuned (lambda, manifoldMediumAngle = "auto"; the angle in degrees), as the
    // farm records it too.
    for (const pf::ChainCounter &c : stats.counters)
        if (c.name == "lambda" || c.name == "mediumAngle")
            image.metadata["pathfarm." + c.name] = std::to_string(c.value);

    const std::string out = a.output.empty() ? pf::client::defaultOutput(a.scene) : a.output;
    std::filesystem::path exr(out), png(out);
    if (exr.extension() != ".exr") exr += ".exr";
    png = exr;
    png.replace_extension(".png");
    if (exr.has_parent_path()) std::filesystem::create_directories(exr.parent_path());
    // The film's formats and tone mapping (hdrfilm's pixelFormat/componentFormat, ldrfilm's tonemapMethod).
    const pf::Film &film = scene->sensor().film();
    pf::writeEXR(exr.string(), image, film.exrFormat());
    pf::writePNG(png.string(), image, film.toneMap(), film.pngPixelFormat());

    const double secs = std::max(stats.seconds, 1e-9);
    const std::string partial =
        pf::partialPassSummary(static_cast<double>(stats.partialPassPixels) / (double(image.width) * image.height));
    std::printf(
        "%s: %dx%d, %lld spp%s, %s, %.2f s render (%.2f s load), %.3g samples/s, %.3g rays/s, %d threads -> %s\n",
        a.scene.c_str(), image.width, image.height, static_cast<long long>(stats.samplesPerPixel), partial.c_str(),
        integrator->name().c_str(), stats.seconds, loadSeconds, stats.samples / secs, stats.rays / secs, opt.threads,
        exr.string().c_str());
    // Markov-chain renders: acceptance per mutation type, then the chains' further statistics.
    for (const pf::MutationCount &c : stats.counts)
        if (c.proposed > 0)
            std::printf("  %-14s %12llu proposed, %5.1f%% accepted\n", c.name.c_str(),
                        static_cast<unsigned long long>(c.proposed), 100.0 * c.accepted / c.proposed);
    for (const pf::ChainCounter &c : stats.counters) std::printf("  %-24s %.6g\n", c.name.c_str(), c.value);
    return 0;
}

}  // namespace

int main(int argc, char **argv) {
    CLI::App app{"pathfarm: a render farm for unbiased light transport"};
    app.require_subcommand(1);
    RenderArgs r;
    CLI::App *render = app.add_subcommand("render", "Render a Mitsuba 0.6 scene on this machine");
    render->add_option("scene", r.scene, "Scene file (Mitsuba 0.5/0.6 XML)")->required();
    render->add_option("-o,--output", r.output, "Output EXR (a tonemapped PNG is written beside it)");
    render->add_option("-i,--integrator", r.integrator,
                       "Integrator (default: the scene's; available: " + pf::integratorNames() + ")");
    render->add_option("--spp", r.spp, "Samples per pixel (default: the scene's sampleCount)")
        ->check(CLI::PositiveNumber);
    render->add_option("--time", r.time, "Wall-time budget in seconds, spent in whole passes")
        ->check(CLI::PositiveNumber);
    render
        ->add_option("--passes", r.passes,
                     "Markov-chain integrators: exactly N passes of a --time render's plan (the same bits as a "
                     "--time render or farm job that ran N passes)")
        ->check(CLI::PositiveNumber);
    render->add_option("--seed", r.seed, "Seed of every random stream");
    render->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::PositiveNumber);
    render->add_option("-D", r.defines, "Scene parameter: -D name=value sets $name");
    render->add_option("-P,--param", r.params, "Integrator parameter: -P name=value (e.g. -P maxDepth=8)");
    render->add_flag("-q,--quiet", r.quiet, "No progress bar");
    render->add_flag("--strict", r.strict,
                     "A parameter that its plugin does not use is an error (exit 2) instead of a warning");
    pf::client::FarmCommands farm(app);
    pf::client::DiffCommand diff(app);
    pf::client::CompareCommand compare(app);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError &e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : pf::kExitBadInput;
    }
    try {
        if (*render) return runRender(r);
        if (const int code = farm.run(); code >= 0) return code;
        if (const int code = diff.run(); code >= 0) return code;
        if (const int code = compare.run(); code >= 0) return code;
    } catch (const pf::SceneError &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return pf::kExitBadInput;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
