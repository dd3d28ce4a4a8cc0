#include "support/chain_util.h"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <vector>

#include "render/seeding.h"

namespace pf::test {

Normalizer seedChains(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed) {
    std::vector<SeedingResult> seeds;
    for (const SeedingTask &t : integrator.seedingTasks(scene))
        seeds.push_back(integrator.runSeeding(scene, 0, seed, t));
    return Normalizer(std::move(seeds));
}

std::string chainResultBytes(const ChainResult &result) {
    // The film's tiles (BlockStorage::Tiles), each after its index: which tiles exist is part of the result.
    std::string bytes;
    const SplatTiles &tiles = *result.film.tiles();
    for (size_t t = 0; t < tiles.tileCount(); ++t)
        if (const std::span<const double> v = tiles.tile(t); !v.empty()) {
            bytes += std::to_string(t) + ":";
            bytes.append(reinterpret_cast<const char *>(v.data()), v.size_bytes());
        }
    bytes += std::to_string(result.mutations);
    for (const MutationCount &c : result.counts)
        bytes += c.name + std::to_string(c.proposed) + "/" + std::to_string(c.accepted);
    return bytes;
}

std::string selfPath() {
    char buf[4096];
    const ssize_t n = readlink("/proc/self/exe", buf, sizeof buf - 1);
    return n > 0 ? std::string(buf, static_cast<size_t>(n)) : "";
}

std::string readFile(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

}  // namespace pf::test
