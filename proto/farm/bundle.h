// Scene bundles: a scene file and every file it references, relative to the scene's directory,
// content-addressed and moved between processes as a manifest followed by the files' bytes. The client
// builds them, the master stores them, workers cache them; all three verify sizes and hashes and refuse
// entries that could reach outside the bundle (absolute paths, '..').
#pragma once
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "farm/hash.h"
#include "farm/job_setup.h"
#include "pathfarm/v1/common.pb.h"

namespace pf::farm {

using pathfarm::v1::BundleChunk;
using pathfarm::v1::BundleManifest;

// The files a scene needs, as paths relative to the scene's directory (the scene file first): files
// named by <include> and <spectrum filename>, and every <string> parameter value that names an existing
// file inside the scene's directory ($name substituted from <default>s and `defines`). Loading the scene
// from the bundle is the final check; this only has to find what the loader will look for.
std::vector<std::string> collectSceneFiles(const std::string &scenePath, const NameValues &defines);

// Reads and hashes `files` (relative to rootDir) into a manifest, sorted by path.
BundleManifest makeManifest(const std::string &rootDir, const std::string &sceneFile, std::vector<std::string> files);

// The bundle's content address: XXH3-128 of a canonical text form of the manifest.
std::string bundleHash(const BundleManifest &manifest);

// Throws FarmError naming the entry when a path is absolute, contains '..', '.', empty components or
// backslashes, is listed twice, when the scene file is not an entry, or when the files together exceed
// maxBytes.
void validateManifest(const BundleManifest &manifest, uint64_t maxBytes);

// Streams a stored bundle: the manifest, then the files' bytes in chunks of at most chunkBytes. `emit`
// returns false when the receiver is gone, which stops the stream.
void streamBundle(const std::string &dir, const BundleManifest &manifest, size_t chunkBytes,
                  const std::function<bool(const BundleChunk &)> &emit);

// A directory of bundles, root/<hash>/ with root/<hash>.manifest beside it; the master's bundle store
// and the workers' scene cache, each owned by one process. Safe to use from several threads: a bundle is
// received into a private directory and renamed into place only when complete and verified.
class BundleStore {
public:
    BundleStore(std::string root, uint64_t maxBytes);
    bool has(const std::string &hash) const;
    std::string dir(const std::string &hash) const;
    BundleManifest manifest(const std::string &hash) const;
    // Receives a bundle from a chunk stream (`next` fills the next chunk, returns false at the end) and
    // returns its hash. If `expectedHash` is not empty the bundle must have that hash. Throws FarmError on
    // any invalid, inconsistent or oversize content.
    std::string receive(const std::function<bool(BundleChunk &)> &next, const std::string &expectedHash = "");

private:
    std::string root_;
    uint64_t maxBytes_;
    std::mutex publishMutex_;
};

}  // namespace pf::farm
