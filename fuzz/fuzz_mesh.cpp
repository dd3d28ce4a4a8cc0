// libFuzzer target: the mesh readers as the loader calls them (PLY, OBJ, Mitsuba .serialized). The first
// byte picks the reader, the rest is the file. Bad files must end in a SceneError.
#include <zlib.h>

#include <cstring>

#include "core/error.h"
#include "fuzz_util.h"
#include "shape/trianglemesh.h"

namespace {

template <typename T>
void put(std::string &out, T v) {
    out.append(reinterpret_cast<const char *>(&v), sizeof v);  // little-endian, as the format (x86)
}

// One mesh of each format: a triangle and a quad's worth of faces.
std::vector<std::string> seeds() {
    const std::string plyHeader =
        "ply\nformat {} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
    const auto header = [&](const std::string &format) {
        std::string h = plyHeader;
        return h.replace(h.find("{}"), 2, format);
    };
    std::string ascii = header("ascii") + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
    std::string binary = header("binary_little_endian");
    for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f}) put(binary, v);
    for (const int f : {0, 1, 2, 0, 2, 3}) {
        if (f == 0) binary += '\3';
        put(binary, f);
    }
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf 1 3 4\n";
    // Mitsuba's .serialized, version 4: format id and version, then a zlib stream of flags (single
    // precision), name, counts, positions and indices; a dictionary of offsets and the count at the end.
    std::string raw;
    put(raw, uint32_t{0x1000});
    raw += std::string("quad") + '\0';
    put(raw, uint64_t{4});
    put(raw, uint64_t{2});
    for (const float v : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 1.f, 0.f}) put(raw, v);
    for (const uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) put(raw, i);
    uLongf packedSize = compressBound(raw.size());
    std::string packed(packedSize, '\0');
    compress(reinterpret_cast<Bytef *>(packed.data()), &packedSize, reinterpret_cast<const Bytef *>(raw.data()),
             raw.size());
    packed.resize(packedSize);
    std::string serialized;
    put(serialized, uint16_t{0x041C});
    put(serialized, uint16_t{4});
    serialized += packed;
    put(serialized, uint64_t{0});
    put(serialized, uint32_t{1});
    return {'\0' + ascii, '\0' + binary, '\1' + obj, '\2' + serialized};
}

}  // namespace

PATHFARM_FUZZ_SEEDS(seeds)

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    try {
        switch (data[0] % 4) {
            case 0:
                pf::readPLY(pf::fuzz::writeInput("mesh.ply", data + 1, size - 1));
                break;
            case 1:
                pf::readOBJ(pf::fuzz::writeInput("mesh.obj", data + 1, size - 1), data[0] & 4);
                break;
            default:
                pf::readSerialized(pf::fuzz::writeInput("mesh.serialized", data + 1, size - 1), data[0] >> 4);
                break;
        }
    } catch (const pf::SceneError &) {
    }
    return 0;
}
