// Wavefront OBJ meshes (Mitsuba 0.6's obj plugin). Parsing is tinyobjloader's; materials (mtllib) are
// ignored, as the scene file assigns BSDFs, and all groups become one mesh (so Mitsuba's `collapse`
// is accepted and always in effect). tinyobjloader silently reads a malformed number as 0 and reports
// bad face indices without the line, so a validation pass over the file runs first and reports those
// problems at their line.
#include <tiny_obj_loader.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "scene/plugins.h"
#include "shape/trianglemesh.h"

namespace pf {

namespace {

std::vector<std::string> splitWhitespace(const std::string &line) {
    std::vector<std::string> tokens;
    std::istringstream in(line);
    for (std::string tok; in >> tok;) tokens.push_back(tok);
    return tokens;
}

// Parses a whole token as a finite number.
bool parseFinite(const std::string &tok, double &value) {
    char *end = nullptr;
    errno = 0;
    value = std::strtod(tok.c_str(), &end);
    return end == tok.c_str() + tok.size() && errno != ERANGE && std::isfinite(value);
}

// Parses one index of a face corner ("7", "-2"); empty means absent. Resolves it to a 0-based index
// among the `count` elements defined so far (OBJ indices are 1-based; negative ones count back).
bool resolveIndex(const std::string &tok, size_t count, long long &index) {
    char *end = nullptr;
    errno = 0;
    const long long i = std::strtoll(tok.c_str(), &end, 10);
    if (end != tok.c_str() + tok.size() || errno == ERANGE || i == 0) return false;
    index = i > 0 ? i - 1 : static_cast<long long>(count) + i;
    return index >= 0 && index < static_cast<long long>(count);
}

// The validation pass: every v/vn/vt line has finite numbers, every face at least three corners whose
// indices refer to elements defined before it.
void validate(const std::string &path, const std::string &text) {
    std::istringstream in(text);
    size_t counts[3] = {0, 0, 0};  // v, vt, vn
    int lineNo = 0;
    for (std::string line; std::getline(in, line);) {
        ++lineNo;
        const auto fail = [&](const std::string &msg) { throw SceneError({path, lineNo}, msg); };
        // tinyobjloader reads a line only up to a NUL, this pass reads it whole: they would disagree on
        // what the line defines (found by fuzz/fuzz_mesh.cpp).
        if (line.find('\0') != std::string::npos) fail("a NUL byte (an OBJ file is text)");
        const std::vector<std::string> tok = splitWhitespace(line);
        if (tok.empty()) continue;
        const std::string &key = tok[0];
        if (key == "v" || key == "vn" || key == "vt") {
            const size_t needed = key == "vt" ? 1 : 3;
            if (tok.size() < needed + 1) fail("'" + key + "' needs at least " + std::to_string(needed) + " numbers");
            for (size_t i = 1; i < tok.size(); ++i) {
                double v;
                if (!parseFinite(tok[i], v)) fail("'" + tok[i] + "' is not a finite number");
            }
            ++counts[key == "v" ? 0 : (key == "vt" ? 1 : 2)];
        } else if (key == "f") {
            if (tok.size() < 4) fail("a face needs at least 3 vertices");
            // tinyobjloader stores corner counts in a byte.
            if (tok.size() > 256) fail("faces with more than 255 vertices are not supported");
            for (size_t i = 1; i < tok.size(); ++i) {
                // v, v/vt, v//vn or v/vt/vn
                std::vector<std::string> parts;
                std::stringstream corner(tok[i]);
                for (std::string p; std::getline(corner, p, '/');) parts.push_back(p);
                if (parts.empty() || parts.size() > 3) fail("malformed face corner '" + tok[i] + "'");
                static const char *names[3] = {"vertex", "texture coordinate", "normal"};
                for (size_t k = 0; k < parts.size(); ++k) {
                    if (k > 0 && parts[k].empty()) continue;
                    long long index;
                    if (!resolveIndex(parts[k], counts[k], index))
                        fail("face corner '" + tok[i] + "': " + names[k] + " index out of range (" +
                             std::to_string(counts[k]) + " defined so far)");
                }
            }
        }
    }
}

}  // namespace

MeshData readOBJ(const std::string &path, bool flipTexCoords) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw SceneError({path, 0}, "cannot open the OBJ file");
    std::stringstream buffer;
    buffer << file.rdbuf();
    const std::string text = buffer.str();
    validate(path, text);

    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::string warn, err;
    std::istringstream in(text);
    if (!tinyobj::LoadObj(&attrib, &shapes, nullptr, &warn, &err, &in, nullptr, /*triangulate=*/false))
        throw SceneError({path, 0}, "cannot parse the OBJ file: " + err);

    // OBJ indexes positions, texture coordinates and normals separately; each distinct combination
    // becomes one mesh vertex.
    MeshData mesh;
    std::map<std::array<int, 3>, uint32_t> vertexOf;
    bool allNormals = true, anyUV = false;
    std::vector<std::array<int, 3>> keys;
    for (const auto &shape : shapes) {
        size_t offset = 0;
        for (const size_t n : shape.mesh.num_face_vertices) {
            std::vector<uint32_t> face;
            for (size_t k = 0; k < n; ++k) {
                const tinyobj::index_t &idx = shape.mesh.indices[offset + k];
                const std::array<int, 3> key = {idx.vertex_index, idx.texcoord_index, idx.normal_index};
                allNormals = allNormals && key[2] >= 0;
                anyUV = anyUV || key[1] >= 0;
                const auto [it, inserted] = vertexOf.emplace(key, static_cast<uint32_t>(keys.size()));
                if (inserted) keys.push_back(key);
                face.push_back(it->second);
            }
            offset += n;
            // Polygons become triangle fans.
            for (size_t k = 1; k + 1 < face.size(); ++k) mesh.triangles.push_back({face[0], face[k], face[k + 1]});
        }
    }
    // The validation pass has checked every index; this guards the arrays should tinyobjloader ever read a
    // line differently.
    const auto defined = [](int index, const std::vector<tinyobj::real_t> &values, size_t dim) {
        return index < 0 || static_cast<size_t>(index) < values.size() / dim;
    };
    for (const auto &key : keys)
        if (key[0] < 0 || !defined(key[0], attrib.vertices, 3) || !defined(key[1], attrib.texcoords, 2) ||
            !defined(key[2], attrib.normals, 3))
            throw SceneError({path, 0}, "a face refers to an element that the file does not define");
    for (const auto &key : keys) {
        const size_t v = static_cast<size_t>(key[0]);
        mesh.positions.emplace_back(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
        // A mesh whose corners only partly carry normals gets generated normals throughout.
        if (allNormals) {
            const size_t n = static_cast<size_t>(key[2]);
            mesh.normals.emplace_back(attrib.normals[3 * n], attrib.normals[3 * n + 1], attrib.normals[3 * n + 2]);
        }
        if (anyUV) {
            // Corners without a texture coordinate get (0, 0). Mitsuba flips v by default (OBJ puts the
            // texture origin at the bottom left).
            Vec2 uv;
            if (key[1] >= 0) {
                const size_t t = static_cast<size_t>(key[1]);
                uv = Vec2(attrib.texcoords[2 * t], attrib.texcoords[2 * t + 1]);
                if (flipTexCoords) uv.y = 1.0 - uv.y;
            }
            mesh.uvs.push_back(uv);
        }
    }
    return mesh;
}

std::shared_ptr<Object> createObj(const Properties &props, const LoadContext &ctx) {
    const std::string path = ctx.resolve(props, "filename");
    const MeshOptions opts = MeshOptions::forMeshFile(props);
    props.getBool("collapse", false);  // all groups always form one mesh
    MeshData data = readOBJ(path, props.getBool("flipTexCoords", true));
    return std::make_shared<TriangleMesh>(props, std::move(data), opts, path);
}

}  // namespace pf
