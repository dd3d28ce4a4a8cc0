// The `pathfarm` command line. `pathfarm render SCENE` renders on this machine (the embedded default);
// the farm commands (submit, watch, fetch, ...) arrive with the farm.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <thread>

#include "core/error.h"
#include "image/bitmap.h"
#include "image/film.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace {

struct RenderArgs {
    std::string scene, output, integrator;
    int64_t spp = 0;
    double time = 0;
    uint64_t seed = 0;
    int threads = 0;
    std::vector<std::string> defines, params;
    bool quiet = false;
};

std::vector<std::pair<std::string, std::string>> parseDefines(const std::vector<std::string> &defs) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const std::string &d : defs) {
        const auto eq = d.find('=');
        if (eq == std::string::npos || eq == 0)
            throw pf::SceneError("-D " + d + ": expected name=value");
        out.emplace_back(d.substr(0, eq), d.substr(eq + 1));
    }
    return out;
}

// -P name=value: an integrator parameter, typed like the scene file would (boolean, integer, float,
// else string), replacing the file's value.
void applyParams(pf::Properties &props, const std::vector<std::string> &params) {
    for (const std::string &p : params) {
        const auto eq = p.find('=');
        if (eq == std::string::npos || eq == 0) throw pf::SceneError("-P " + p + ": expected name=value");
        const std::string name = p.substr(0, eq), value = p.substr(eq + 1);
        const pf::SourceLocation loc{"command line (-P " + p + ")", 0};
        props.remove(name);
        char *end = nullptr;
        if (value == "true" || value == "false") {
            props.set(name, pf::Properties::Type::Boolean, value == "true", loc);
        } else if (const long long i = std::strtoll(value.c_str(), &end, 10); !value.empty() && *end == '\0') {
            props.set(name, pf::Properties::Type::Integer, static_cast<int64_t>(i), loc);
        } else if (const double d = std::strtod(value.c_str(), &end); !value.empty() && *end == '\0') {
            props.set(name, pf::Properties::Type::Float, d, loc);
        } else {
            props.set(name, pf::Properties::Type::String, value, loc);
        }
    }
}

std::string defaultOutput(const std::string &scenePath) {
    std::filesystem::path p(scenePath);
    const std::string stem = p.stem() == "scene" && p.has_parent_path() ? p.parent_path().filename().string()
                                                                           : p.stem().string();
    return stem + ".exr";
}

int runRender(const RenderArgs &a) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    auto scene = pf::loadScene(a.scene, parseDefines(a.defines));
    const double loadSeconds = std::chrono::duration<double>(Clock::now() - t0).count();

    const pf::Properties &fileProps = scene->integratorProperties();
    const std::string fileType = fileProps.pluginName().empty() ? "path" : fileProps.pluginName();
    const std::string type = a.integrator.empty() ? fileType : a.integrator;
    // The file's parameters are checked strictly when they were written for this integrator; when the
    // CLI picks another one, shared parameters (maxDepth, rrDepth, ...) carry over and the rest is ignored.
    pf::Properties props = type == fileType ? fileProps : pf::Properties(pf::ObjectKind::Integrator, type, {});
    if (type != fileType)
        for (const char *shared : {"maxDepth", "rrDepth", "strictNormals", "hideEmitters"})
            if (fileProps.has(shared)) props.set(shared, fileProps.type(shared), fileProps.value(shared), fileProps.locationOf(shared));
    applyParams(props, a.params);
    auto integrator = pf::createIntegrator(type, props, true);

    pf::RenderOptions opt;
    opt.spp = a.spp;
    opt.timeLimit = a.time;
    opt.seed = a.seed;
    opt.threads = a.threads > 0 ? a.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    opt.progress = !a.quiet;
    pf::RenderStats stats;
    pf::Bitmap image = integrator->render(*scene, opt, stats);

    image.metadata["pathfarm.integrator"] = integrator->name();
    image.metadata["pathfarm.spp"] = std::to_string(stats.samplesPerPixel);
    image.metadata["pathfarm.seed"] = std::to_string(a.seed);
    image.metadata["pathfarm.renderSeconds"] = std::to_string(stats.seconds);
    image.metadata["pathfarm.sceneLoadSeconds"] = std::to_string(loadSeconds);
    image.metadata["pathfarm.scene"] = a.scene;

    const std::string out = a.output.empty() ? defaultOutput(a.scene) : a.output;
    std::filesystem::path exr(out), png(out);
    if (exr.extension() != ".exr") exr += ".exr";
    png = exr;
    png.replace_extension(".png");
    if (exr.has_parent_path()) std::filesystem::create_directories(exr.parent_path());
    pf::writeEXR(exr.string(), image);
    pf::writePNG(png.string(), image, scene->sensor().film().exposure());

    const double secs = std::max(stats.seconds, 1e-9);
    std::printf("%s: %dx%d, %lld spp, %s, %.2f s render (%.2f s load), %.3g samples/s, %.3g rays/s, %d threads -> %s\n",
                a.scene.c_str(), image.width, image.height, static_cast<long long>(stats.samplesPerPixel),
                integrator->name().c_str(), stats.seconds, loadSeconds, stats.samples / secs, stats.rays / secs,
                opt.threads, exr.string().c_str());
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
    render->add_option("-i,--integrator", r.integrator, "Integrator (default: the scene's; available: " +
                                                            pf::integratorNames() + ")");
    render->add_option("--spp", r.spp, "Samples per pixel (default: the scene's sampleCount)")
        ->check(CLI::PositiveNumber);
    render->add_option("--time", r.time, "Wall-time budget in seconds, spent in whole passes")
        ->check(CLI::PositiveNumber);
    render->add_option("--seed", r.seed, "Seed of every random stream");
    render->add_option("--threads", r.threads, "Worker threads (default: all cores)")->check(CLI::PositiveNumber);
    render->add_option("-D", r.defines, "Scene parameter: -D name=value sets $name");
    render->add_option("-P,--param", r.params, "Integrator parameter: -P name=value (e.g. -P maxDepth=8)");
    render->add_flag("-q,--quiet", r.quiet, "No progress bar");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError &e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : pf::kExitBadInput;
    }
    try {
        if (*render) return runRender(r);
    } catch (const pf::SceneError &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return pf::kExitBadInput;
    } catch (const std::exception &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
