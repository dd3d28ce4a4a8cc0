// Mitsuba's .serialized meshes (Mitsuba 0.6 TriMesh::loadCompressed). A file is a sequence of meshes,
// each a little-endian header (uint16 format id 0x041C, uint16 version 3 or 4) followed by a zlib
// stream holding
//   uint32 flags; [v4: the mesh name, null-terminated]; uint64 vertexCount; uint64 triangleCount;
//   positions (3 per vertex); [normals (3)]; [texture coordinates (2)]; [colours (3)]; uint32 indices,
// with floats in single precision, or double with the 0x2000 flag. The file ends with a dictionary of
// the meshes' byte offsets (uint64 in version 4, uint32 in version 3) and a uint32 mesh count, which
// shapeIndex is looked up in.
#include <zlib.h>

#include <bit>
#include <cstring>
#include <fstream>
#include <sstream>

#include "scene/plugins.h"
#include "shape/trianglemesh.h"

namespace pf {

namespace {

constexpr uint16_t kFormatId = 0x041C;
enum SerializedFlags : uint32_t {
    HasNormals = 0x0001,
    HasTexCoords = 0x0002,
    HasColors = 0x0008,
    FaceNormals = 0x0010,
    DoublePrecision = 0x2000,
};
// zlib's deflate expands data by at most a factor of 1032; counts that would need more input than the
// file holds are corrupt, and refusing them keeps a damaged header from allocating gigabytes.
constexpr double kMaxInflateRatio = 1032.0;

template <typename T>
T fromLittleEndian(const unsigned char *b) {
    unsigned char tmp[sizeof(T)];
    std::memcpy(tmp, b, sizeof(T));
    if constexpr (std::endian::native == std::endian::big) std::reverse(tmp, tmp + sizeof(T));
    T v;
    std::memcpy(&v, tmp, sizeof(T));
    return v;
}

// Inflates one mesh's zlib stream straight into the destination arrays.
class ZReader {
public:
    ZReader(const std::string &path, const unsigned char *data, size_t size) : path_(path) {
        std::memset(&zs_, 0, sizeof(zs_));
        if (inflateInit(&zs_) != Z_OK) throw SceneError({path_, 0}, "cannot initialize zlib");
        zs_.next_in = const_cast<unsigned char *>(data);
        zs_.avail_in = static_cast<uInt>(std::min<size_t>(size, UINT32_MAX));
    }
    ~ZReader() { inflateEnd(&zs_); }
    ZReader(const ZReader &) = delete;
    ZReader &operator=(const ZReader &) = delete;

    void read(void *dst, size_t n) {
        auto *out = static_cast<unsigned char *>(dst);
        while (n > 0) {
            bool ended;
            const size_t produced = step(out, n, ended);
            out += produced;
            n -= produced;
            if (n > 0 && ended) throw SceneError({path_, 0}, "the mesh data is truncated");
        }
    }
    // Inflates the rest of the stream, so that its checksum is verified (trailing data is ignored).
    void finish() {
        unsigned char scratch[256];
        for (bool ended = false; !ended;) step(scratch, sizeof(scratch), ended);
    }
    template <typename T>
    T value() {
        unsigned char b[sizeof(T)];
        read(b, sizeof(T));
        return fromLittleEndian<T>(b);
    }
    // count tuples of `dim` floats, stored in single or double precision.
    std::vector<double> reals(size_t count, int dim, bool dbl) {
        const size_t n = count * dim, width = dbl ? 8 : 4;
        std::vector<unsigned char> raw(n * width);
        read(raw.data(), raw.size());
        std::vector<double> out(n);
        for (size_t i = 0; i < n; ++i)
            out[i] = dbl ? fromLittleEndian<double>(&raw[i * 8]) : fromLittleEndian<float>(&raw[i * 4]);
        return out;
    }

private:
    // One inflate call into out[0, n); returns the bytes produced and whether the stream ended.
    size_t step(unsigned char *out, size_t n, bool &ended) {
        const uInt chunk = static_cast<uInt>(std::min<size_t>(n, UINT32_MAX));
        zs_.next_out = out;
        zs_.avail_out = chunk;
        const int rc = inflate(&zs_, Z_NO_FLUSH);
        // Z_BUF_ERROR: no progress is possible, i.e. the input ran out.
        if (rc == Z_BUF_ERROR) throw SceneError({path_, 0}, "the mesh data is truncated");
        if (rc != Z_OK && rc != Z_STREAM_END)
            throw SceneError({path_, 0},
                             std::string("corrupt compressed mesh data (zlib: ") + (zs_.msg ? zs_.msg : "error") + ")");
        ended = rc == Z_STREAM_END;
        return chunk - zs_.avail_out;
    }

    std::string path_;
    z_stream zs_;
};

}  // namespace

MeshData readSerialized(const std::string &path, int64_t shapeIndex) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw SceneError({path, 0}, "cannot open the serialized mesh file");
    std::stringstream buffer;
    buffer << file.rdbuf();
    const std::string text = buffer.str();
    const auto *bytes = reinterpret_cast<const unsigned char *>(text.data());
    const size_t size = text.size();
    const auto fail = [&](const std::string &msg) { throw SceneError({path, 0}, msg); };

    const auto header = [&](size_t at) {
        if (size < 4 || at > size - 4) fail("the file is truncated");
        const uint16_t format = fromLittleEndian<uint16_t>(bytes + at);
        if (format != kFormatId) fail("not a Mitsuba serialized mesh (bad format id)");
        const uint16_t version = fromLittleEndian<uint16_t>(bytes + at + 2);
        if (version != 3 && version != 4) fail("unsupported serialized mesh version " + std::to_string(version));
        return version;
    };
    size_t offset = 0;
    uint16_t version = header(0);
    if (shapeIndex > 0) {
        // The dictionary's layout is that of the file's first mesh version (as in Mitsuba).
        const uint32_t count = fromLittleEndian<uint32_t>(bytes + size - 4);
        if (static_cast<uint64_t>(shapeIndex) >= count)
            fail("shapeIndex " + std::to_string(shapeIndex) + " is out of range: the file holds " +
                 std::to_string(count) + " meshes");
        const size_t entry = version == 4 ? 8 : 4;
        const uint64_t back = 4 + entry * (count - static_cast<uint64_t>(shapeIndex));
        if (back > size) fail("the mesh dictionary is truncated");
        offset = version == 4 ? fromLittleEndian<uint64_t>(bytes + size - back)
                              : fromLittleEndian<uint32_t>(bytes + size - back);
        version = header(offset);
    }

    const size_t compressed = size - offset - 4;
    ZReader z(path, bytes + offset + 4, compressed);
    const uint32_t flags = z.value<uint32_t>();
    if (version == 4) {
        // The name: a null-terminated string, bounded so that a corrupt stream cannot run on.
        for (size_t len = 0;; ++len) {
            if (len > 65536) fail("corrupt mesh name");
            if (z.value<char>() == '\0') break;
        }
    }
    const uint64_t vertexCount = z.value<uint64_t>(), triangleCount = z.value<uint64_t>();
    const bool dbl = (flags & DoublePrecision) != 0;
    const double perVertex = (dbl ? 8.0 : 4.0) * (3 + ((flags & HasNormals) ? 3 : 0) +
                                                  ((flags & HasTexCoords) ? 2 : 0) + ((flags & HasColors) ? 3 : 0));
    if (vertexCount >= UINT32_MAX ||
        perVertex * static_cast<double>(vertexCount) + 12.0 * static_cast<double>(triangleCount) >
            kMaxInflateRatio * static_cast<double>(compressed) + 1024.0)
        fail("corrupt mesh header (" + std::to_string(vertexCount) + " vertices, " + std::to_string(triangleCount) +
             " triangles)");

    MeshData mesh;
    mesh.faceNormals = (flags & FaceNormals) != 0;
    const std::vector<double> p = z.reals(vertexCount, 3, dbl);
    for (size_t i = 0; i < vertexCount; ++i) mesh.positions.emplace_back(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    if (flags & HasNormals) {
        const std::vector<double> n = z.reals(vertexCount, 3, dbl);
        for (size_t i = 0; i < vertexCount; ++i) mesh.normals.emplace_back(n[3 * i], n[3 * i + 1], n[3 * i + 2]);
    }
    if (flags & HasTexCoords) {
        const std::vector<double> t = z.reals(vertexCount, 2, dbl);
        for (size_t i = 0; i < vertexCount; ++i) mesh.uvs.emplace_back(t[2 * i], t[2 * i + 1]);
    }
    if (flags & HasColors) z.reals(vertexCount, 3, dbl);  // vertex colours are not used
    std::vector<unsigned char> idx(triangleCount * 12);
    z.read(idx.data(), idx.size());
    mesh.triangles.resize(triangleCount);
    for (size_t t = 0; t < triangleCount; ++t)
        for (int k = 0; k < 3; ++k) mesh.triangles[t][k] = fromLittleEndian<uint32_t>(&idx[12 * t + 4 * k]);
    z.finish();
    return mesh;
}

std::shared_ptr<Object> createSerialized(const Properties &props, const LoadContext &ctx) {
    const std::string path = ctx.resolve(props, "filename");
    const int64_t shapeIndex = props.getInt("shapeIndex", 0);
    if (shapeIndex < 0) props.fail("shapeIndex", "must not be negative");
    const MeshOptions opts = MeshOptions::forMeshFile(props);
    return std::make_shared<TriangleMesh>(props, readSerialized(path, shapeIndex), opts, path);
}

}  // namespace pf
