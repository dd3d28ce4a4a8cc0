// The reference of a comparison when none is given: the scene rendered with BDPT at a high sample count
// on the same farm, cached by what determines it (the scene bundle's content hash, the -D definitions,
// maxDepth, the sample count and the seed), so repeated comparisons of a scene render it once.
#pragma once
#include <string>

#include "compare_report.h"
#include "farm_client.h"
#include "image/bitmap.h"

namespace pf::client {

struct ReferenceRequest {
    std::string cacheDir;  // "" = defaultReferenceCacheDir()
    int64_t spp = 0;
    uint64_t seed = 0;
    NameValues defines;
    NameValues params;    // of the compared runs; only maxDepth (which changes the integral) is passed on
    bool strict = false;  // compare --strict (does not change the image, so not part of the cache key)
};

// $XDG_CACHE_HOME/pathfarm/references, else $HOME/.cache/pathfarm/references.
std::string defaultReferenceCacheDir();

// The cached reference, or a fresh render on the farm, which is then cached. Fills `info` (source
// "cache" or "rendered", the cache file, integrator, spp, render time).
Bitmap obtainReference(pathfarm::v1::ClientService::Stub &stub, const FarmConnection &farm, const SceneBundle &scene,
                       const ReferenceRequest &request, ReferenceInfo &info);

}  // namespace pf::client
