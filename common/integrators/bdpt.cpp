// The integrator is a short sequence of path-space calls ([TH A4]: "our implementation of BDPT creates
// two subpaths that initially only contain endpoint supernodes, and repeatedly calls the SAMPLENEXT
// operation ... Following this, the CONNECT function is invoked on every pair of vertices"); the
// strategies' densities and weights live in path/.
#include "integrators/bdpt.h"

#include <spdlog/fmt/fmt.h>

#include <filesystem>

#include "image/bitmap.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The subpaths and buffers of one evaluate call, kept per thread, so that a sample allocates nothing once
// they have grown (issue 17: a malloc and free per subpath and buffer showed in the profiles). A visitor
// that evaluates again inside a call gets buffers of its own.
struct Workspace {
    Path camera, light;
    JoinedPath path;
    std::vector<Vec2> emitterDirect, sensorDirect;
    PathDensities densities;
    bool busy = false;
};

class WorkspaceLease {
public:
    WorkspaceLease() : workspace_(perThread_.busy ? nested_.emplace() : perThread_) { workspace_.busy = true; }
    ~WorkspaceLease() { workspace_.busy = false; }
    WorkspaceLease(const WorkspaceLease &) = delete;
    WorkspaceLease &operator=(const WorkspaceLease &) = delete;
    Workspace &operator*() const { return workspace_; }

private:
    static thread_local Workspace perThread_;
    std::optional<Workspace> nested_;
    Workspace &workspace_;
};

thread_local Workspace WorkspaceLease::perThread_;

}  // namespace

BDPT::BDPT(const Properties &props) {
    maxDepth_ = static_cast<int>(props.getInt("maxDepth", -1));
    rrDepth_ = static_cast<int>(props.getInt("rrDepth", 5));
    mis_.lightImage = props.getBool("lightImage", true);
    mis_.sampleDirect = props.getBool("sampleDirect", true);
    const std::string heuristic = props.getString("heuristic", "power");
    strategyImages_ = props.getString("strategyImages", "");
    if (maxDepth_ < -1 || maxDepth_ == 0) props.fail("maxDepth", "must be -1 (unbounded) or at least 1");
    if (rrDepth_ < 1) props.fail("rrDepth", "must be at least 1");
    if (heuristic == "power")
        mis_.exponent = 2.0;
    else if (heuristic == "balance")
        mis_.exponent = 1.0;
    else
        props.fail("heuristic", "must be 'power' or 'balance' (got '" + heuristic + "')");
    if (!strategyImages_.empty() && maxDepth_ < 0)
        props.fail("strategyImages", "needs a finite maxDepth (one image per strategy)");
}

void BDPT::evaluate(const Scene &scene, Sampler &sampler, const Vec2 &raster, const StrategyVisitor &visit,
                    std::optional<Strategy> only, int minDepth) const {
    // A path of n vertices has n - 1 edges; the emitter walk takes one vertex more than it can connect,
    // so that its last edge can still cross the lens (t = 0).
    const int maxVertices = maxDepth_ < 0 ? -1 : maxDepth_ + 1;
    const WorkspaceLease lease;
    Workspace &w = *lease;
    Path &camera = w.camera, &light = w.light;
    JoinedPath &path = w.path;
    std::vector<Vec2> &emitterDirect = w.emitterDirect, &sensorDirect = w.sensorDirect;
    // Each walk and the direct-sampling numbers start at their own place in a low-discrepancy sampler's
    // sequence (Sampler::startPart), so that the emitter walk's first vertices and the direct samples stay
    // stratified across a pixel's samples whatever the camera walk consumed before them.
    camera.sample(scene, sampler, TransportMode::Radiance, maxVertices, rrDepth_, raster);
    sampler.startPart(1);
    light.sample(scene, sampler, TransportMode::Importance, maxVertices, rrDepth_);
    sampler.startPart(2);
    emitterDirect.clear();
    sensorDirect.clear();
    if (mis_.sampleDirect) {
        for (int t = 2; t <= camera.size(); ++t) emitterDirect.push_back(sampler.next2D());
        for (int s = 2; s <= light.size(); ++s) sensorDirect.push_back(sampler.next2D());
    }

    // A path's depth is s + t - 1 plus the pass-through surfaces its edges cross (path.h).
    const bool crossings = scene.hasPassThroughSurfaces();
    const auto wanted = [&](int s, int t) {
        return (!only || *only == Strategy(s, t)) && (maxDepth_ < 0 || s + t - 1 <= maxDepth_) &&
               (crossings || s + t - 1 >= minDepth) && (mis_.lightImage || t >= 2);
    };
    // s + t - 1 <= maxDepth above prunes strategies early; the index-matched surfaces that the path's
    // edges cross count too (Mitsuba's bdpt_proc.cpp lets a connection bridge only maxDepth - s - t + 1
    // of them), which only the built path knows. All strategies of a path share its depth, so the MIS
    // weights need no change.
    const auto report = [&](int s, int t) {
        // Without pass-through surfaces no edge crosses one, and the depth is the s + t - 1 bounded above.
        const int depth = crossings ? pathDepth(path) : path.length() - 1;
        if ((maxDepth_ >= 0 && depth > maxDepth_) || depth < minDepth) return;
        path.densities(scene, mis_.sampleDirect, w.densities);
        const double weight = misWeight(w.densities, s, mis_);
        visit({s, t, depth, path.raster(), weight, path.contribution() * weight, &path});
    };
    for (int t = 1; t <= camera.size(); ++t)
        for (int s = 0; s <= light.size(); ++s) {
            if (!wanted(s, t)) continue;
            bool built;
            if (s == 0)
                built = t >= 2 && path.hitEmitter(scene, camera, t);
            else if (s == 1 && t >= 2 && mis_.sampleDirect)
                built = path.connectDirectEmitter(scene, emitterDirect[static_cast<size_t>(t - 2)], camera, t);
            else if (t == 1 && s >= 2 && mis_.sampleDirect)
                built = path.connectDirectSensor(scene, sensorDirect[static_cast<size_t>(s - 2)], light, s);
            else
                built = path.connect(scene, light, s, camera, t);
            if (built) report(s, t);
        }
    for (const LensHit &hit : light.lensHits())
        if (wanted(hit.from + 2, 0) && path.hitLens(scene, light, hit)) report(hit.from + 2, 0);
}

Spectrum BDPT::sample(const Scene &scene, Sampler &sampler, const Vec2 &raster, SplatList &splats) const {
    Spectrum L;
    evaluate(
        scene, sampler, raster,
        [&](const StrategySample &x) {
            if (x.t >= 2)
                L += x.value;
            else
                splats.push_back({x.raster, x.value});
        },
        only_);
    return L;
}

Spectrum BDPT::Li(const Scene &scene, Sampler &sampler, const Ray &ray) const {
    Vec2 raster;
    if (!scene.sensor().rasterPosition(ray.o, ray.d, raster)) return {};
    Spectrum L;
    evaluate(scene, sampler, raster, [&](const StrategySample &x) {
        if (x.t >= 2) L += x.value;
    });
    return L;
}

bool BDPT::regenerate(const Scene &scene, uint64_t seed, const PathRecord &record, const StrategyVisitor &visit) const {
    const Film &film = scene.sensor().film();
    const uint64_t width = static_cast<uint64_t>(film.width());
    const Vec2 pixel(static_cast<double>(record.pixel % width) - film.cropX(),
                     static_cast<double>(record.pixel / width) - film.cropY());
    IndependentSampler sampler(seed, record.pixel, record.sampleIndex);
    const Vec2 raster = pixel + sampler.next2D();
    bool found = false;
    evaluate(
        scene, sampler, raster,
        [&](const StrategySample &x) {
            found = true;
            visit(x);
        },
        Strategy(record.s, record.t));
    return found;
}

std::vector<StrategyImage> BDPT::renderStrategyImages(const Scene &scene, const RenderOptions &opt) const {
    if (maxDepth_ < 0) throw SceneError("bdpt: per-strategy images need a finite maxDepth");
    RenderOptions quiet = opt;
    quiet.progress = false;
    quiet.onPass = nullptr;
    std::vector<StrategyImage> images;
    for (int n = 2; n <= maxDepth_ + 1; ++n)
        for (int t = n; t >= 0; --t) {
            if ((t == 0 && scene.sensor().deltaAperture()) || (!mis_.lightImage && t <= 1)) continue;
            BDPT single = *this;
            single.only_ = Strategy(n - t, t);
            RenderStats stats;
            images.push_back({*single.only_, single.SamplingIntegrator::render(scene, quiet, stats)});
        }
    return images;
}

Bitmap BDPT::render(const Scene &scene, const RenderOptions &opt, RenderStats &stats) const {
    Bitmap image = SamplingIntegrator::render(scene, opt, stats);
    if (strategyImages_.empty()) return image;
    // The same samples as the image just rendered, also when it was rendered to a time budget (whose partial
    // last pass, if any, they leave out).
    RenderOptions same = opt;
    same.timeLimit = 0;
    same.spp = stats.samplesPerPixel;
    std::filesystem::create_directories(strategyImages_);
    for (const StrategyImage &si : renderStrategyImages(scene, same)) {
        const std::string name = fmt::format("s{}_t{}.exr", si.strategy.first, si.strategy.second);
        writeEXR((std::filesystem::path(strategyImages_) / name).string(), si.image);
    }
    return image;
}

}  // namespace pf
