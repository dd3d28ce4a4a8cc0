// Stanford PLY meshes (Mitsuba 0.6's ply plugin), ASCII and binary in either byte order (Paul Bourke's
// description of the format, as written by Greg Turk's original ply library). The "vertex" element
// supplies x y z, optionally nx ny nz and texture coordinates (u v, s t, texture_u texture_v or
// texture_s texture_t); the "face" element a vertex_indices (or vertex_index) list per polygon, which
// is triangulated as a fan. Other elements and properties (colours, edges, materials) are skipped.
#include <bit>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>

#include "scene/plugins.h"
#include "shape/trianglemesh.h"

namespace pf {

namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<PlyType> parseType(const std::string &name) {
    static const std::pair<const char *, PlyType> names[] = {
        {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (const auto &[n, t] : names)
        if (name == n) return t;
    return std::nullopt;
}

size_t typeSize(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 0;
}

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool isList = false;
    PlyType countType = PlyType::UInt8;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> props;
    int index(const std::string &name) const {
        for (size_t i = 0; i < props.size(); ++i)
            if (props[i].name == name) return static_cast<int>(i);
        return -1;
    }
};

enum class PlyFormat { Ascii, BinaryLittleEndian, BinaryBigEndian };

// Sequential reader of the body: whitespace-separated numbers (ASCII) or packed binary values.
class PlyBody {
public:
    PlyBody(const std::string &path, const std::string &text, size_t pos, PlyFormat format, int line)
        : path_(path), text_(text), pos_(pos), format_(format), line_(line) {}

    double read(PlyType type) { return format_ == PlyFormat::Ascii ? readAscii(type) : readBinary(type); }
    // A list length: a non-negative integer.
    uint64_t readCount(PlyType type) {
        const double n = read(type);
        if (!(n >= 0) || n != std::floor(n)) fail("invalid list length " + std::to_string(n));
        return static_cast<uint64_t>(n);
    }
    // ASCII errors name the line; binary ones the element instance (`what`).
    [[noreturn]] void fail(const std::string &msg) const {
        if (format_ == PlyFormat::Ascii) throw SceneError({path_, line_}, msg);
        throw SceneError({path_, 0}, where_ + ": " + msg);
    }
    void setContext(const std::string &where) { where_ = where; }

private:
    double readAscii(PlyType type) {
        while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
            if (text_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= text_.size()) fail("unexpected end of file");
        const size_t start = pos_;
        while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
        const std::string tok = text_.substr(start, pos_ - start);
        char *end = nullptr;
        errno = 0;
        const double v = std::strtod(tok.c_str(), &end);
        if (end != tok.c_str() + tok.size() || errno == ERANGE || !std::isfinite(v))
            fail("'" + tok + "' is not a finite number");
        if (type != PlyType::Float32 && type != PlyType::Float64 && v != std::floor(v))
            fail("'" + tok + "' is not an integer");
        return v;
    }

    double readBinary(PlyType type) {
        const size_t n = typeSize(type);
        if (text_.size() - pos_ < n) fail("unexpected end of file");
        unsigned char b[8];
        std::memcpy(b, text_.data() + pos_, n);
        pos_ += n;
        const bool fileBig = format_ == PlyFormat::BinaryBigEndian;
        if (fileBig != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
        switch (type) {
            case PlyType::Int8:
                return static_cast<int8_t>(b[0]);
            case PlyType::UInt8:
                return b[0];
            case PlyType::Int16:
                return load<int16_t>(b);
            case PlyType::UInt16:
                return load<uint16_t>(b);
            case PlyType::Int32:
                return load<int32_t>(b);
            case PlyType::UInt32:
                return load<uint32_t>(b);
            case PlyType::Float32:
                return load<float>(b);
            case PlyType::Float64:
                return load<double>(b);
        }
        return 0;
    }
    template <typename T>
    static double load(const unsigned char *b) {
        T v;
        std::memcpy(&v, b, sizeof(T));
        return static_cast<double>(v);
    }

    const std::string &path_, &text_;
    size_t pos_;
    PlyFormat format_;
    int line_;
    std::string where_;
};

// Reads one property of an element instance: a scalar's value, or a list, which is discarded (0).
double readProperty(PlyBody &body, const PlyProperty &p) {
    if (!p.isList) return body.read(p.type);
    const uint64_t n = body.readCount(p.countType);
    for (uint64_t k = 0; k < n; ++k) body.read(p.type);
    return 0.0;
}

}  // namespace

MeshData readPLY(const std::string &path) {
    std::ifstream file(path, std::ios::binary);
    if (!file) throw SceneError({path, 0}, "cannot open the PLY file");
    std::stringstream buffer;
    buffer << file.rdbuf();
    const std::string text = buffer.str();

    // Header: lines up to end_header.
    size_t pos = 0;
    int lineNo = 0;
    std::optional<PlyFormat> format;
    std::vector<PlyElement> elements;
    for (bool done = false; !done;) {
        if (pos >= text.size()) throw SceneError({path, lineNo}, "the PLY header has no end_header");
        const size_t eol = text.find('\n', pos);
        const std::string line = text.substr(pos, eol == std::string::npos ? std::string::npos : eol - pos);
        pos = eol == std::string::npos ? text.size() : eol + 1;
        ++lineNo;
        const auto fail = [&](const std::string &msg) { throw SceneError({path, lineNo}, msg); };
        std::istringstream in(line);
        std::string key;
        in >> key;
        if (lineNo == 1) {
            if (key != "ply") fail("not a PLY file (missing 'ply' magic)");
            continue;
        }
        if (key == "format") {
            std::string f, version;
            in >> f >> version;
            if (f == "ascii")
                format = PlyFormat::Ascii;
            else if (f == "binary_little_endian")
                format = PlyFormat::BinaryLittleEndian;
            else if (f == "binary_big_endian")
                format = PlyFormat::BinaryBigEndian;
            else
                fail("unknown PLY format '" + f + "'");
        } else if (key == "element") {
            PlyElement e;
            std::string count;
            in >> e.name >> count;
            char *end = nullptr;
            errno = 0;
            e.count = std::strtoull(count.c_str(), &end, 10);
            if (e.name.empty() || count.empty() || count[0] == '-' || *end != '\0' || errno == ERANGE)
                fail("malformed element declaration");
            elements.push_back(e);
        } else if (key == "property") {
            if (elements.empty()) fail("property declared before any element");
            std::string type;
            in >> type;
            PlyProperty p;
            if (type == "list") {
                std::string countType, itemType;
                in >> countType >> itemType;
                const auto ct = parseType(countType), it = parseType(itemType);
                if (!ct || !it) fail("unknown property type in '" + line + "'");
                p.isList = true;
                p.countType = *ct;
                p.type = *it;
            } else {
                const auto t = parseType(type);
                if (!t) fail("unknown property type '" + type + "'");
                p.type = *t;
            }
            in >> p.name;
            if (p.name.empty()) fail("property without a name");
            elements.back().props.push_back(p);
        } else if (key == "end_header") {
            done = true;
        } else if (key != "comment" && key != "obj_info" && !key.empty()) {
            fail("unknown PLY header keyword '" + key + "'");
        }
    }
    if (!format) throw SceneError({path, lineNo}, "the PLY header has no format line");

    const PlyElement *vertexElem = nullptr;
    for (const PlyElement &e : elements)
        if (e.name == "vertex") vertexElem = &e;
    if (!vertexElem) throw SceneError({path, 0}, "the PLY file has no vertex element");
    if (vertexElem->count >= UINT32_MAX) throw SceneError({path, 0}, "too many vertices");
    const uint64_t vertexCount = vertexElem->count;

    MeshData mesh;
    PlyBody body(path, text, pos, *format, lineNo + 1);
    for (const PlyElement &e : elements) {
        if (e.props.empty()) continue;  // nothing stored per instance
        if (e.name == "vertex") {
            const int x = e.index("x"), y = e.index("y"), z = e.index("z");
            const int nx = e.index("nx"), ny = e.index("ny"), nz = e.index("nz");
            int tu = -1, tv = -1;
            for (const auto &[a, b] :
                 {std::pair{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}})
                if (tu < 0 && e.index(a) >= 0 && e.index(b) >= 0) {
                    tu = e.index(a);
                    tv = e.index(b);
                }
            if (x < 0 || y < 0 || z < 0) throw SceneError({path, 0}, "the vertex element lacks x, y or z");
            const bool normals = nx >= 0 && ny >= 0 && nz >= 0;
            std::vector<double> values(e.props.size());
            for (uint64_t i = 0; i < e.count; ++i) {
                body.setContext("vertex " + std::to_string(i));
                for (size_t k = 0; k < e.props.size(); ++k) values[k] = readProperty(body, e.props[k]);
                const Vec3 p(values[x], values[y], values[z]);
                if (!p.isFinite()) body.fail("vertex " + std::to_string(i) + " has a non-finite coordinate");
                mesh.positions.push_back(p);
                if (normals) mesh.normals.emplace_back(values[nx], values[ny], values[nz]);
                if (tu >= 0) mesh.uvs.emplace_back(values[tu], values[tv]);
            }
        } else if (e.name == "face") {
            int li = e.index("vertex_indices");
            if (li < 0) li = e.index("vertex_index");
            if (li < 0 || !e.props[li].isList)
                throw SceneError({path, 0}, "the face element lacks a vertex_indices list");
            for (uint64_t i = 0; i < e.count; ++i) {
                body.setContext("face " + std::to_string(i));
                for (size_t k = 0; k < e.props.size(); ++k) {
                    const PlyProperty &p = e.props[k];
                    if (static_cast<int>(k) != li) {
                        readProperty(body, p);
                        continue;
                    }
                    const uint64_t n = body.readCount(p.countType);
                    if (n < 3) body.fail("face " + std::to_string(i) + " has fewer than 3 vertices");
                    std::vector<uint32_t> face;
                    for (uint64_t j = 0; j < n; ++j) {
                        const double idx = body.read(p.type);
                        if (!(idx >= 0 && idx < static_cast<double>(vertexCount)) || idx != std::floor(idx))
                            body.fail("face " + std::to_string(i) + " refers to vertex " + std::to_string(idx) +
                                      ", but there are only " + std::to_string(vertexCount) + " vertices");
                        face.push_back(static_cast<uint32_t>(idx));
                    }
                    for (size_t j = 1; j + 1 < face.size(); ++j)
                        mesh.triangles.push_back({face[0], face[j], face[j + 1]});
                }
            }
        } else {
            for (uint64_t i = 0; i < e.count; ++i) {
                body.setContext(e.name + " " + std::to_string(i));
                for (const PlyProperty &p : e.props) readProperty(body, p);
            }
        }
    }
    return mesh;
}

std::shared_ptr<Object> createPly(const Properties &props, const LoadContext &ctx) {
    const std::string path = ctx.resolve(props, "filename");
    const MeshOptions opts = MeshOptions::forMeshFile(props);
    props.getBool("srgb", true);  // Mitsuba's gamma flag for vertex colours, which are not used
    return std::make_shared<TriangleMesh>(props, readPLY(path), opts, path);
}

}  // namespace pf
