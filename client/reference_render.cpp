#include "reference_render.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "farm/hash.h"
#include "farm_job.h"

namespace pf::client {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

namespace {

constexpr const char *kReferenceIntegrator = "bdpt";

}  // namespace

std::string defaultReferenceCacheDir() {
    if (const char *x = std::getenv("XDG_CACHE_HOME"); x && *x) return (fs::path(x) / "pathfarm/references").string();
    if (const char *h = std::getenv("HOME"); h && *h) return (fs::path(h) / ".cache/pathfarm/references").string();
    throw std::runtime_error("no cache directory for references: set HOME or XDG_CACHE_HOME, or give --cache-dir");
}

Bitmap obtainReference(v1::ClientService::Stub &stub, const FarmConnection &farm, const SceneBundle &scene,
                       const ReferenceRequest &request, ReferenceInfo &info) {
    NameValues params;
    for (const auto &p : request.params)
        if (p.first == "maxDepth") params.push_back(p);
    std::string key = "bundle=" + scene.hash + "\nintegrator=" + kReferenceIntegrator +
                      "\nspp=" + std::to_string(request.spp) + "\nseed=" + std::to_string(request.seed);
    for (const auto &[n, v] : request.defines) key += "\n-D " + n + "=" + v;
    for (const auto &[n, v] : params) key += "\n-P " + n + "=" + v;
    const fs::path dir = request.cacheDir.empty() ? defaultReferenceCacheDir() : request.cacheDir;
    const fs::path file = dir / (farm::hashHex128(key) + ".exr");
    info.cacheFile = file.string();
    info.integrator = kReferenceIntegrator;
    info.spp = request.spp;
    if (fs::is_regular_file(file)) {
        Bitmap image = readEXR(file.string());
        info.source = "cache";
        if (const auto it = image.metadata.find("pathfarm.renderSeconds"); it != image.metadata.end())
            info.renderSeconds = std::atof(it->second.c_str());
        std::fprintf(stderr, "compare: reference from the cache, %s\n", file.c_str());
        return image;
    }
    v1::JobSpec spec;
    spec.set_bundle_hash(scene.hash);
    spec.set_integrator(kReferenceIntegrator);
    setParams(*spec.mutable_params(), params);
    setParams(*spec.mutable_defines(), request.defines);
    spec.mutable_budget()->set_spp(request.spp);
    spec.set_seed(request.seed);
    spec.set_label("reference of " + scene.sceneFile);
    spec.set_strict(request.strict);
    std::fprintf(stderr, "compare: rendering the reference (%s, %lld spp) on the farm\n", kReferenceIntegrator,
                 static_cast<long long>(request.spp));
    const FinishedJob done = runJob(stub, farm, spec);
    // Written under a temporary name and renamed, so that an interrupted write never leaves a bad cache entry.
    fs::create_directories(dir);
    const fs::path tmp = file.string() + ".partial";
    writeBytes(tmp.string(), done.image.exr);
    fs::rename(tmp, file);
    info.source = "rendered";
    info.renderSeconds = done.job.render_seconds();
    return readEXR(file.string());
}

}  // namespace pf::client
