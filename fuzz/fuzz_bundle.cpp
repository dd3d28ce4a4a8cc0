// libFuzzer target: the scene-bundle parser and its path checks as the master's UploadBundle (and a
// worker's FetchBundle) receive a bundle: length-prefixed BundleChunks (2 bytes, little-endian, then the
// message) into a BundleStore, which validates the manifest (absolute paths, '..', duplicates, sizes)
// and every file's size and hash before it publishes the bundle. Bad input must end in a FarmError, and
// nothing may be written outside the store.
#include <filesystem>

#include "farm/bundle.h"
#include "farm/error.h"
#include "fuzz_util.h"

namespace {

// A valid bundle: a scene that includes a part, as the client streams it.
std::vector<std::string> seeds() {
    const std::vector<std::pair<std::string, std::string>> files = {
        {"parts/light.xml", "<scene version=\"0.5.0\"/>"},
        {"scene.xml", "<scene version=\"0.5.0\"><include filename=\"parts/light.xml\"/></scene>"}};
    pf::farm::BundleChunk manifest, data;
    manifest.mutable_manifest()->set_scene_file("scene.xml");
    for (const auto &[path, content] : files) {
        auto *e = manifest.mutable_manifest()->add_entries();
        e->set_path(path);
        e->set_size(content.size());
        e->set_hash(pf::farm::hashHex64(content));
        *data.mutable_data() += content;
    }
    return {pf::fuzz::frame(manifest) + pf::fuzz::frame(data)};
}

}  // namespace

PATHFARM_FUZZ_SEEDS(seeds)

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static pf::farm::BundleStore store(pf::fuzz::workDir() + "/bundles", 1 << 20);
    pf::fuzz::FrameReader frames(data, size);
    const auto next = [&](pf::farm::BundleChunk &chunk) { return frames(chunk); };
    try {
        const std::string hash = store.receive(next);
        // A bundle that passed is published: drop it, so that the next input is received afresh.
        std::filesystem::remove_all(store.dir(hash));
        std::filesystem::remove(store.dir(hash) + ".manifest");
    } catch (const pf::farm::FarmError &) {
    }
    // Whatever arrived, nothing lies beside the store.
    for (const auto &e : std::filesystem::directory_iterator(pf::fuzz::workDir()))
        if (e.path().filename() != "bundles") __builtin_trap();
    return 0;
}
