// Mitsuba 0.5/0.6 XML scene loader (format: Mitsuba 0.6 documentation, chapter 6 "Scene file format";
// behaviour follows Mitsuba 0.6's SceneHandler). The document is parsed with pugixml into a DOM and then
// walked in document order, so that <default>, ids and transform composition behave as in Mitsuba's
// streaming parser. Every problem becomes a SceneError naming the file and line.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <pugixml.hpp>
#include <sstream>

#include "core/frame.h"
#include "scene/plugins.h"
#include "scene/scene.h"
#include "scene/spectrum_convert.h"

namespace pf {

namespace fs = std::filesystem;

namespace {

// Deeper nesting than any real scene uses; bounds the recursion of the DOM walk on hostile input.
constexpr int kMaxDepth = 64;

// Object elements and the kind of plugin each one instantiates.
const std::map<std::string, ObjectKind> &objectTags() {
    static const std::map<std::string, ObjectKind> tags = {
        {"shape", ObjectKind::Shape},     {"bsdf", ObjectKind::BSDF},       {"texture", ObjectKind::Texture},
        {"emitter", ObjectKind::Emitter}, {"sensor", ObjectKind::Sensor},   {"film", ObjectKind::Film},
        {"rfilter", ObjectKind::RFilter}, {"sampler", ObjectKind::Sampler}, {"integrator", ObjectKind::Integrator},
        {"medium", ObjectKind::Medium},   {"phase", ObjectKind::Phase},
    };
    return tags;
}

// The attributes each element accepts (Mitsuba 0.6's schema, data/schema/scene.xsd, plus the
// value="x, y, z" triples and rotate axis="..." that later Mitsuba versions also write). Anything
// else is a typo that would otherwise be ignored silently.
const std::vector<std::string> *allowedAttributes(const std::string &tag) {
    static const std::map<std::string, std::vector<std::string>> table = {
        {"scene", {"version"}},
        {"ref", {"id", "name"}},
        {"integer", {"name", "value"}},
        {"float", {"name", "value"}},
        {"boolean", {"name", "value"}},
        {"string", {"name", "value"}},
        {"rgb", {"name", "value", "intent"}},
        {"srgb", {"name", "value", "intent"}},
        {"spectrum", {"name", "value", "filename", "intent"}},
        {"blackbody", {"name", "temperature", "scale"}},
        {"point", {"name", "x", "y", "z", "value"}},
        {"vector", {"name", "x", "y", "z", "value"}},
        {"transform", {"name"}},
        {"translate", {"x", "y", "z", "value"}},
        {"rotate", {"x", "y", "z", "axis", "angle"}},
        {"scale", {"x", "y", "z", "value"}},
        {"matrix", {"value"}},
        {"lookat", {"origin", "target", "up"}},
        {"lookAt", {"origin", "target", "up"}},
        {"include", {"filename"}},
        {"default", {"name", "value"}},
        {"alias", {"id", "as"}},
    };
    static const std::vector<std::string> objectAttributes = {"type", "id", "name"};
    if (objectTags().count(tag)) return &objectAttributes;
    const auto it = table.find(tag);
    return it == table.end() ? nullptr : &it->second;
}

std::string trim(const std::string &s) {
    const auto b = s.find_first_not_of(" \t\r\n");
    if (b == std::string::npos) return "";
    return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

// Splits Mitsuba value lists, which separate numbers by commas and/or whitespace.
std::vector<std::string> splitList(const std::string &s) {
    std::vector<std::string> out;
    std::string cur;
    for (char c : s) {
        if (c == ',' || c == ' ' || c == '\t' || c == '\n' || c == '\r') {
            if (!cur.empty()) out.push_back(std::move(cur));
            cur.clear();
        } else {
            cur += c;
        }
    }
    if (!cur.empty()) out.push_back(std::move(cur));
    return out;
}

// One XML file being parsed: its name for messages, its directory, and a line index for offsets.
struct SourceFile {
    std::string path;  // as shown in messages
    std::string dir;   // directory that relative file names resolve against
    std::vector<ptrdiff_t> lineStarts;

    SourceLocation at(ptrdiff_t offset) const {
        const auto it = std::upper_bound(lineStarts.begin(), lineStarts.end(), std::max<ptrdiff_t>(offset, 0));
        return {path, static_cast<int>(it - lineStarts.begin())};
    }
};

// An element with its attributes already $-substituted and checked against the schema.
class Element {
public:
    Element(pugi::xml_node node, SourceLocation loc, std::map<std::string, std::string> attrs)
        : node_(node), loc_(std::move(loc)), attrs_(std::move(attrs)) {}

    pugi::xml_node node() const { return node_; }
    std::string tag() const { return node_.name(); }
    const SourceLocation &loc() const { return loc_; }
    bool has(const std::string &name) const { return attrs_.count(name) != 0; }
    const std::string &attr(const std::string &name) const {
        const auto it = attrs_.find(name);
        if (it == attrs_.end()) fail("missing attribute '" + name + "'");
        return it->second;
    }
    std::optional<std::string> optional(const std::string &name) const {
        const auto it = attrs_.find(name);
        return it == attrs_.end() ? std::nullopt : std::optional<std::string>(it->second);
    }
    [[noreturn]] void fail(const std::string &msg) const { throw SceneError(loc_, "<" + tag() + ">: " + msg); }

    // A finite number in the given attribute text. std::from_chars accepts exactly the decimal
    // floating-point syntax (no trailing garbage, no locale); "nan" and "inf" parse but are refused.
    double number(const std::string &text, const std::string &what) const {
        std::string s = trim(text);
        if (!s.empty() && s[0] == '+') s.erase(0, 1);
        double v = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec == std::errc::invalid_argument || end != s.data() + s.size())
            fail("malformed number '" + text + "' in " + what);
        if (ec == std::errc::result_out_of_range || !std::isfinite(v))
            fail("'" + text + "' in " + what + " is not a finite number");
        return v;
    }
    double number(const std::string &attrName) const { return number(attr(attrName), "attribute '" + attrName + "'"); }

    // Three numbers from value="x, y, z", or from x/y/z attributes (missing ones take `def` if given).
    Vec3 triple(std::optional<double> def) const {
        const bool xyz = has("x") || has("y") || has("z");
        if (has("value")) {
            if (xyz) fail("give either 'value' or 'x', 'y', 'z', not both");
            const auto tokens = splitList(attr("value"));
            if (tokens.size() != 3) fail("'value' needs three numbers, got '" + attr("value") + "'");
            return {number(tokens[0], "'value'"), number(tokens[1], "'value'"), number(tokens[2], "'value'")};
        }
        Vec3 v;
        for (int i = 0; i < 3; ++i) {
            const std::string a(1, "xyz"[i]);
            if (has(a))
                v[i] = number(a);
            else if (def)
                v[i] = *def;
            else
                fail("missing attribute '" + a + "'");
        }
        return v;
    }

    // A list of exactly three numbers in one attribute (lookat's origin, target, up).
    Vec3 listTriple(const std::string &attrName) const {
        const auto tokens = splitList(attr(attrName));
        if (tokens.size() != 3) fail("'" + attrName + "' needs three numbers, got '" + attr(attrName) + "'");
        const std::string what = "attribute '" + attrName + "'";
        return {number(tokens[0], what), number(tokens[1], what), number(tokens[2], what)};
    }

private:
    pugi::xml_node node_;
    SourceLocation loc_;
    std::map<std::string, std::string> attrs_;
};

// The plugin interface a top-level object must implement; a factory registered under the wrong kind
// would otherwise hand the scene a null pointer.
template <class T>
std::shared_ptr<T> as(const Element &e, const std::shared_ptr<Object> &obj) {
    auto cast = std::dynamic_pointer_cast<T>(obj);
    if (!cast) e.fail("plugin '" + e.attr("type") + "' does not implement this object kind");
    return cast;
}

struct NamedObject {
    ObjectKind kind;
    std::shared_ptr<Object> object;
    SourceLocation loc;
};

class Loader {
public:
    Loader(Scene &scene, const std::vector<std::pair<std::string, std::string>> &defines, std::string rootDir,
           UnusedParameters &unused)
        : scene_(scene), rootDir_(std::move(rootDir)), unused_(unused) {
        for (const auto &[name, value] : defines) params_[name] = value;
    }

    // Parses one scene file (the top-level one, or an included one) into the scene; returns the
    // location of its <scene> element.
    SourceLocation parseFile(const std::string &absPath, const std::string &displayPath);

    void finish(const SourceLocation &sceneLoc);

private:
    Element element(pugi::xml_node node, const SourceFile &file) const;
    std::string substitute(const std::string &raw, const SourceLocation &loc, const std::string &tag) const;
    void checkVersion(const Element &scene) const;

    void sceneChild(const Element &e, const SourceFile &file);
    std::shared_ptr<Object> parseObject(const Element &e, ObjectKind kind, const SourceFile &file, int depth);
    Properties parseProperties(const Element &e, ObjectKind kind, const SourceFile &file, int depth);
    void include(const Element &e, const SourceFile &file);
    void setDefault(const Element &e);
    void registerId(const std::string &id, ObjectKind kind, std::shared_ptr<Object> obj, const SourceLocation &loc);

    void setParameter(const Element &e, Properties &props, const SourceFile &file) const;
    Spectrum parseColor(const Element &e, bool srgb) const;
    Spectrum parseSpectrum(const Element &e, const SourceFile &file) const;
    Spectrum readSpectrumFile(const Element &e, const SourceFile &file) const;
    Transform parseTransform(const Element &e, const SourceFile &file) const;

    Scene &scene_;
    std::string rootDir_;
    UnusedParameters &unused_;
    std::map<std::string, std::string> params_;
    std::map<std::string, NamedObject> objects_;
    std::vector<std::string> includeStack_;
    std::optional<SourceLocation> sensorLoc_, integratorLoc_;
};

std::string readWholeFile(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    if (!in) throw SceneError(SourceLocation{path, 0}, "cannot read file");
    return ss.str();
}

SourceLocation Loader::parseFile(const std::string &absPath, const std::string &displayPath) {
    const std::string text = readWholeFile(absPath);
    SourceFile file{displayPath, fs::path(absPath).parent_path().string(), {0}};
    for (size_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') file.lineStarts.push_back(static_cast<ptrdiff_t>(i + 1));

    pugi::xml_document doc;
    const pugi::xml_parse_result result =
        doc.load_buffer(text.data(), text.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!result) throw SceneError(file.at(result.offset), std::string("XML parse error: ") + result.description());

    const pugi::xml_node root = doc.document_element();
    if (std::string(root.name()) != "scene")
        throw SceneError(file.at(root.offset_debug()),
                         "the root element must be <scene>, not <" + std::string(root.name()) + ">");
    const Element scene = element(root, file);
    checkVersion(scene);

    includeStack_.push_back(absPath);
    for (pugi::xml_node child : root.children())
        if (child.type() == pugi::node_element) sceneChild(element(child, file), file);
    includeStack_.pop_back();
    return scene.loc();
}

Element Loader::element(pugi::xml_node node, const SourceFile &file) const {
    const SourceLocation loc = file.at(node.offset_debug());
    const std::string tag = node.name();
    const auto *allowed = allowedAttributes(tag);
    if (!allowed) {
        // Mitsuba 0.4 renamed these; 0.3 scenes that use them need the (mechanical) upgrade.
        const std::string hint = tag == "camera"      ? " (Mitsuba 0.3 syntax: write <sensor>)"
                                 : tag == "luminaire" ? " (Mitsuba 0.3 syntax: write <emitter>)"
                                                      : "";
        throw SceneError(loc, "unknown element <" + tag + ">" + hint);
    }
    std::map<std::string, std::string> attrs;
    for (pugi::xml_attribute a : node.attributes()) {
        const std::string name = a.name();
        if (std::find(allowed->begin(), allowed->end(), name) == allowed->end())
            throw SceneError(loc, "<" + tag + ">: unknown attribute '" + name + "'");
        attrs[name] = substitute(a.value(), loc, tag);
    }
    // Only objects, <scene> and <transform> have nested elements; anything inside a parameter would
    // otherwise be dropped without a word.
    if (!objectTags().count(tag) && tag != "scene" && tag != "transform")
        for (pugi::xml_node child : node.children())
            if (child.type() == pugi::node_element)
                throw SceneError(file.at(child.offset_debug()),
                                 "<" + tag + "> cannot contain <" + std::string(child.name()) + ">");
    return Element(node, loc, std::move(attrs));
}

// $name substitution (Mitsuba 0.6: in every attribute, from <default> values and -D command-line
// definitions, the latter taking precedence). Where several defined names match at a '$', the longest
// wins, so $spp and $sppMax can coexist; an unmatched '$' is an error as in Mitsuba.
std::string Loader::substitute(const std::string &raw, const SourceLocation &loc, const std::string &tag) const {
    if (raw.find('$') == std::string::npos) return raw;
    std::string out;
    for (size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] != '$') {
            out += raw[i];
            continue;
        }
        const std::string *best = nullptr;
        for (const auto &[name, value] : params_)
            if (raw.compare(i + 1, name.size(), name) == 0 && (!best || name.size() > best->size())) best = &name;
        if (!best) {
            size_t j = i + 1;
            while (j < raw.size() && (std::isalnum(static_cast<unsigned char>(raw[j])) || raw[j] == '_')) ++j;
            throw SceneError(loc, "<" + tag + ">: undefined parameter '$" + raw.substr(i + 1, j - i - 1) +
                                      "' (define it with <default> or -D)");
        }
        out += params_.at(*best);
        i += best->size();
    }
    return out;
}

// Mitsuba 0.3 made the version attribute mandatory. The 0.x format changed little up to 0.6 (0.4
// renamed <camera>/<luminaire> to <sensor>/<emitter>; the old names get a hint in element()), while
// Mitsuba 2 and 3 renamed most parameters (to_world, ...), so their scenes are refused up front.
void Loader::checkVersion(const Element &scene) const {
    if (!scene.has("version")) scene.fail("missing 'version' attribute (write e.g. <scene version=\"0.6.0\">)");
    const std::string &v = scene.attr("version");
    std::vector<int> parts;
    std::string cur;
    for (char c : v + ".") {
        if (c != '.') {
            if (!std::isdigit(static_cast<unsigned char>(c)) || cur.size() > 6)
                scene.fail("malformed version '" + v + "'");
            cur += c;
            continue;
        }
        if (cur.empty()) scene.fail("malformed version '" + v + "'");
        parts.push_back(std::stoi(cur));
        cur.clear();
    }
    if (parts.size() < 2 || parts.size() > 3) scene.fail("malformed version '" + v + "'");
    if (parts[0] >= 2)
        scene.fail("scene version " + v +
                   ": Mitsuba 2/3 syntax is not supported; pathfarm reads Mitsuba 0.5/0.6 scenes");
    if (parts[0] != 0 || parts[1] < 3 || parts[1] > 6)
        scene.fail("unsupported scene version " + v + " (expected 0.3.0 to 0.6.x)");
}

void Loader::sceneChild(const Element &e, const SourceFile &file) {
    const std::string tag = e.tag();
    const auto kindIt = objectTags().find(tag);
    if (kindIt == objectTags().end()) {
        if (tag == "include") return include(e, file);
        if (tag == "default") return setDefault(e);
        if (tag == "alias") {
            const auto it = objects_.find(e.attr("id"));
            if (it == objects_.end()) e.fail("unknown id '" + e.attr("id") + "'");
            return registerId(e.attr("as"), it->second.kind, it->second.object, e.loc());
        }
        e.fail("not allowed directly inside <scene>");
    }
    switch (kindIt->second) {
        case ObjectKind::Integrator:
            if (integratorLoc_)
                e.fail("only one <integrator> is allowed (first on line " + std::to_string(integratorLoc_->line) + ")");
            integratorLoc_ = e.loc();
            // The integrator is built later by the renderer, which checks its own parameters.
            scene_.setIntegratorProperties(parseProperties(e, ObjectKind::Integrator, file, 1));
            return;
        case ObjectKind::Shape: {
            // A portal (scene/portal.h) is a top-level rectangle that the rectangle plugin returns as such.
            const auto object = parseObject(e, ObjectKind::Shape, file, 1);
            if (auto p = std::dynamic_pointer_cast<const Portal>(object)) return scene_.addPortal(std::move(p));
            scene_.addShape(as<Shape>(e, object));
            return;
        }
        case ObjectKind::Emitter:
            scene_.addEmitter(as<Emitter>(e, parseObject(e, ObjectKind::Emitter, file, 1)));
            return;
        case ObjectKind::Sensor:
            if (sensorLoc_)
                e.fail("only one <sensor> is supported (first on line " + std::to_string(sensorLoc_->line) + ")");
            sensorLoc_ = e.loc();
            scene_.setSensor(as<Sensor>(e, parseObject(e, ObjectKind::Sensor, file, 1)));
            return;
        case ObjectKind::BSDF:
        case ObjectKind::Texture:
        case ObjectKind::Medium:
        case ObjectKind::Phase:
            // Declared once at the top and used through <ref id="..."/>.
            if (!e.has("id")) e.fail("a top-level <" + tag + "> needs an 'id' so that it can be referenced");
            parseObject(e, kindIt->second, file, 1);
            return;
        default:
            e.fail("must be nested inside the object that uses it (e.g. <film> inside <sensor>)");
    }
}

void Loader::include(const Element &e, const SourceFile &file) {
    // Same resolution rules as every other file name (relative, inside the bundle, must exist).
    Properties p(ObjectKind::Scene, "include", e.loc());
    p.set("filename", Properties::Type::String, e.attr("filename"), e.loc());
    const std::string path = LoadContext{file.dir, rootDir_}.resolve(p, "filename");
    if (std::find(includeStack_.begin(), includeStack_.end(), path) != includeStack_.end()) {
        std::string chain;
        for (const auto &f : includeStack_) chain += fs::path(f).filename().string() + " -> ";
        e.fail("include cycle: " + chain + fs::path(path).filename().string());
    }
    parseFile(path, path);
}

// <default name value>: Mitsuba 0.6 applies it only if the parameter is not yet defined, so values
// given on the command line (and earlier defaults) take precedence.
void Loader::setDefault(const Element &e) {
    const std::string &name = e.attr("name");
    if (name.empty() || !std::all_of(name.begin(), name.end(),
                                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }))
        e.fail("invalid parameter name '" + name + "'");
    params_.emplace(name, e.attr("value"));
}

void Loader::registerId(const std::string &id, ObjectKind kind, std::shared_ptr<Object> obj,
                        const SourceLocation &loc) {
    const auto [it, inserted] = objects_.emplace(id, NamedObject{kind, std::move(obj), loc});
    if (!inserted) throw SceneError(loc, "duplicate id '" + id + "' (first defined at " + it->second.loc.str() + ")");
}

Properties Loader::parseProperties(const Element &e, ObjectKind kind, const SourceFile &file, int depth) {
    if (depth > kMaxDepth) e.fail("elements nested more than " + std::to_string(kMaxDepth) + " deep");
    const std::string type = e.attr("type");
    Properties props(kind, type, e.loc());
    if (e.has("id")) props.setId(e.attr("id"));

    // Parameters and named children share one namespace (a texture slot may be filled either way).
    std::map<std::string, int> names;
    auto claimName = [&](const Element &c, const std::string &name) {
        if (name.empty()) return;
        const auto [it, inserted] = names.emplace(name, c.loc().line);
        if (!inserted)
            c.fail("duplicate parameter '" + name + "' (first set on line " + std::to_string(it->second) + ")");
    };

    for (pugi::xml_node node : e.node().children()) {
        if (node.type() != pugi::node_element) continue;
        const Element c = element(node, file);
        const std::string tag = c.tag();
        const auto kindIt = objectTags().find(tag);
        if (kindIt != objectTags().end()) {
            if (kindIt->second == ObjectKind::Integrator) c.fail("nested integrators are not supported");
            const std::string name = c.optional("name").value_or("");
            claimName(c, name);
            props.addChild({name, kindIt->second, parseObject(c, kindIt->second, file, depth + 1), c.loc()});
        } else if (tag == "ref") {
            const std::string &id = c.attr("id");
            const auto it = objects_.find(id);
            if (it == objects_.end()) c.fail("reference to unknown id '" + id + "'");
            const std::string name = c.optional("name").value_or("");
            claimName(c, name);
            props.addChild({name, it->second.kind, it->second.object, c.loc()});
        } else if (tag == "default") {
            setDefault(c);
        } else if (tag == "include" || tag == "alias") {
            c.fail("only allowed directly inside <scene>");
        } else if (tag == "scene" || tag == "translate" || tag == "rotate" || tag == "scale" || tag == "matrix" ||
                   tag == "lookat" || tag == "lookAt") {
            c.fail(tag == "scene" ? "<scene> cannot be nested" : "only allowed inside <transform>");
        } else {
            claimName(c, c.attr("name"));
            setParameter(c, props, file);
        }
    }
    return props;
}

std::shared_ptr<Object> Loader::parseObject(const Element &e, ObjectKind kind, const SourceFile &file, int depth) {
    const std::string type = e.attr("type");
    const PluginFactory *factory = findPlugin(kind, type);
    if (!factory) {
        std::string known;
        for (const auto &n : pluginNames(kind)) known += (known.empty() ? "" : ", ") + n;
        e.fail("unknown " + std::string(objectKindName(kind)) + " type '" + type +
               "' (known: " + (known.empty() ? "none yet" : known) + ")");
    }
    if (e.has("id") && objects_.count(e.attr("id")))
        e.fail("duplicate id '" + e.attr("id") + "' (first defined at " + objects_.at(e.attr("id")).loc.str() + ")");

    const Properties props = parseProperties(e, kind, file, depth);
    std::shared_ptr<Object> obj;
    try {
        obj = (*factory)(props, LoadContext{file.dir, rootDir_});
        props.checkUsed(unused_);
    } catch (const SceneError &err) {
        // Errors located in this XML file are already precise; others (a mesh or image reader's
        // "file:line" in the asset, or no location at all) get the element's location prefixed.
        if (err.location().file == file.path) throw;
        throw SceneError(e.loc(), type + ": " + err.what());
    } catch (const std::exception &err) {
        throw SceneError(e.loc(), type + ": " + err.what());
    }
    if (!obj) e.fail("plugin '" + type + "' produced no object");
    obj->setIdentity(e.optional("id").value_or(""), e.loc());
    if (e.has("id")) registerId(e.attr("id"), kind, obj, e.loc());
    return obj;
}

void Loader::setParameter(const Element &e, Properties &props, const SourceFile &file) const {
    using T = Properties::Type;
    const std::string tag = e.tag();
    const std::string &name = e.attr("name");
    if (tag == "integer") {
        const std::string s = trim(e.attr("value"));
        int64_t v = 0;
        const char *begin = s.data() + (!s.empty() && s[0] == '+' ? 1 : 0);
        const auto [end, ec] = std::from_chars(begin, s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || end != s.data() + s.size())
            e.fail("malformed integer '" + e.attr("value") + "'");
        props.set(name, T::Integer, v, e.loc());
    } else if (tag == "float") {
        props.set(name, T::Float, e.number("value"), e.loc());
    } else if (tag == "boolean") {
        const std::string &s = e.attr("value");
        if (s != "true" && s != "false") e.fail("boolean value must be 'true' or 'false', got '" + s + "'");
        props.set(name, T::Boolean, s == "true", e.loc());
    } else if (tag == "string") {
        props.set(name, T::String, e.attr("value"), e.loc());
    } else if (tag == "rgb" || tag == "srgb") {
        props.set(name, T::Spectrum, parseColor(e, tag == "srgb"), e.loc());
    } else if (tag == "spectrum") {
        props.set(name, T::Spectrum, parseSpectrum(e, file), e.loc());
    } else if (tag == "blackbody") {
        // Mitsuba writes temperatures with an optional unit suffix ("6500K").
        std::string t = trim(e.attr("temperature"));
        if (!t.empty() && (t.back() == 'K' || t.back() == 'k')) t.pop_back();
        const double temperature = e.number(t, "attribute 'temperature'");
        if (!(temperature > 0)) e.fail("temperature must be positive");
        const double scale = e.has("scale") ? e.number("scale") : 1.0;
        props.set(name, T::Spectrum, blackbodyToRGB(temperature) * scale, e.loc());
    } else if (tag == "point" || tag == "vector") {
        props.set(name, tag == "point" ? T::Point : T::Vector, e.triple(std::nullopt), e.loc());
    } else if (tag == "transform") {
        props.set(name, T::Transform, parseTransform(e, file), e.loc());
    } else {
        e.fail("unexpected element");
    }
}

// <rgb> holds linear values and <srgb> gamma-encoded ones; both take one grey value, three values, or
// an HTML-style "#rrggbb" (Mitsuba 0.6). The 'intent' attribute only matters in Mitsuba's spectral
// builds; it is validated and otherwise has no effect in RGB mode.
Spectrum Loader::parseColor(const Element &e, bool srgb) const {
    if (const auto intent = e.optional("intent"); intent && *intent != "reflectance" && *intent != "illuminant")
        e.fail("intent must be 'reflectance' or 'illuminant', got '" + *intent + "'");
    const auto tokens = splitList(e.attr("value"));
    Spectrum s;
    if (tokens.size() == 1 && tokens[0][0] == '#') {
        const std::string &hex = tokens[0];
        unsigned v = 0;
        const auto [end, ec] = std::from_chars(hex.data() + 1, hex.data() + hex.size(), v, 16);
        if (hex.size() != 7 || ec != std::errc() || end != hex.data() + hex.size())
            e.fail("malformed colour '" + hex + "' (expected #rrggbb)");
        s = Spectrum(((v >> 16) & 0xff) / 255.0, ((v >> 8) & 0xff) / 255.0, (v & 0xff) / 255.0);
    } else if (tokens.size() == 1) {
        s = Spectrum(e.number(tokens[0], "'value'"));
    } else if (tokens.size() == 3) {
        s = Spectrum(e.number(tokens[0], "'value'"), e.number(tokens[1], "'value'"), e.number(tokens[2], "'value'"));
    } else {
        e.fail("expected one value, three values or #rrggbb, got '" + e.attr("value") + "'");
    }
    if (srgb)
        for (int i = 0; i < 3; ++i) s[i] = srgbToLinear(s[i]);
    return s;
}

// <spectrum>: a single value (grey), "wavelength:value" pairs, three plain values (Mitsuba compiled in
// RGB mode reads them as RGB), or a filename of a two-column wavelength/value file.
Spectrum Loader::parseSpectrum(const Element &e, const SourceFile &file) const {
    if (e.has("value") == e.has("filename")) e.fail("give exactly one of 'value' and 'filename'");
    if (e.has("intent") && e.attr("intent") != "reflectance" && e.attr("intent") != "illuminant")
        e.fail("intent must be 'reflectance' or 'illuminant', got '" + e.attr("intent") + "'");
    if (e.has("filename")) return readSpectrumFile(e, file);
    const std::string &value = e.attr("value");
    const auto tokens = splitList(value);
    if (tokens.empty()) e.fail("empty 'value'");
    if (value.find(':') == std::string::npos) {
        if (tokens.size() == 1) return Spectrum(e.number(tokens[0], "'value'"));
        if (tokens.size() == 3)
            return {e.number(tokens[0], "'value'"), e.number(tokens[1], "'value'"), e.number(tokens[2], "'value'")};
        e.fail("expected one value, three values or wavelength:value pairs, got '" + value + "'");
    }
    SampledSpectrum samples;
    for (const auto &tok : tokens) {
        const auto colon = tok.find(':');
        if (colon == std::string::npos) e.fail("expected wavelength:value, got '" + tok + "'");
        samples.emplace_back(e.number(tok.substr(0, colon), "'value'"), e.number(tok.substr(colon + 1), "'value'"));
    }
    try {
        return sampledSpectrumToRGB(samples);
    } catch (const std::invalid_argument &err) {
        e.fail(err.what());
    }
}

// Mitsuba's InterpolatedSpectrum file format: one "wavelength value" pair per line, '#' comments.
Spectrum Loader::readSpectrumFile(const Element &e, const SourceFile &file) const {
    Properties p(ObjectKind::Scene, "spectrum", e.loc());
    p.set("filename", Properties::Type::String, e.attr("filename"), e.loc());
    const std::string path = LoadContext{file.dir, rootDir_}.resolve(p, "filename");
    std::ifstream in(path);
    SampledSpectrum samples;
    std::string line;
    for (int lineNo = 1; std::getline(in, line); ++lineNo) {
        const std::string content = trim(line.substr(0, line.find('#')));
        if (content.empty()) continue;
        const auto tokens = splitList(content);
        const std::string where = e.attr("filename") + " line " + std::to_string(lineNo);
        if (tokens.size() != 2) e.fail("expected 'wavelength value' in " + where);
        samples.emplace_back(e.number(tokens[0], where), e.number(tokens[1], where));
    }
    try {
        return sampledSpectrumToRGB(samples);
    } catch (const std::invalid_argument &err) {
        e.fail(e.attr("filename") + ": " + err.what());
    }
}

// Transform elements compose in document order, each applied after the previous ones (T = step * T),
// as in Mitsuba 0.6's SceneHandler.
Transform Loader::parseTransform(const Element &e, const SourceFile &file) const {
    Transform t;
    for (pugi::xml_node node : e.node().children()) {
        if (node.type() != pugi::node_element) continue;
        const Element c = element(node, file);
        const std::string tag = c.tag();
        Transform step;
        try {
            if (tag == "translate") {
                step = Transform::translate(c.triple(0.0));
            } else if (tag == "rotate") {
                Vec3 axis;
                if (c.has("axis")) {
                    if (c.has("x") || c.has("y") || c.has("z")) c.fail("give either 'axis' or 'x', 'y', 'z'");
                    axis = c.listTriple("axis");
                } else {
                    axis = c.triple(0.0);
                }
                step = Transform::rotate(axis, c.number("angle"));
            } else if (tag == "scale") {
                const bool uniform = c.has("value") && splitList(c.attr("value")).size() == 1;
                step = Transform::scale(uniform ? Vec3(c.number("value")) : c.triple(1.0));
            } else if (tag == "matrix") {
                const auto tokens = splitList(c.attr("value"));
                if (tokens.size() != 16) c.fail("needs 16 values, got " + std::to_string(tokens.size()));
                Matrix4 m;
                for (int i = 0; i < 16; ++i) m.m[i / 4][i % 4] = c.number(tokens[i], "'value'");
                step = Transform(m);
            } else if (tag == "lookat" || tag == "lookAt") {
                const Vec3 origin = c.listTriple("origin"), target = c.listTriple("target");
                if ((target - origin).isZero()) c.fail("'origin' and 'target' coincide");
                Vec3 up, unused;
                if (c.has("up"))
                    up = c.listTriple("up");
                else  // Mitsuba picks an arbitrary perpendicular axis when 'up' is omitted.
                    coordinateSystem(normalize(target - origin), up, unused);
                step = Transform::lookAt(origin, target, up);
            } else {
                c.fail("not allowed inside <transform>");
            }
        } catch (const std::invalid_argument &err) {
            c.fail(std::string("singular transform: ") + err.what());
        }
        t = step * t;
        if (!t.matrix().isFinite() || !t.inverseMatrix().isFinite())
            c.fail("transform overflows (or becomes singular) after this step");
    }
    return t;
}

void Loader::finish(const SourceLocation &sceneLoc) {
    if (!scene_.sensorPtr()) throw SceneError(sceneLoc, "the scene has no <sensor>");
    try {
        scene_.finalize();
    } catch (const SceneError &err) {
        if (!err.location().file.empty()) throw;
        throw SceneError(sceneLoc, err.what());
    } catch (const std::exception &err) {
        throw SceneError(sceneLoc, err.what());
    }
}

}  // namespace

std::unique_ptr<Scene> loadScene(const std::string &path,
                                 const std::vector<std::pair<std::string, std::string>> &defines, bool strict) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw SceneError(SourceLocation{path, 0}, "scene file not found");
    const fs::path abs = fs::absolute(path).lexically_normal();
    auto scene = std::make_unique<Scene>();
    UnusedParameters unused(strict);
    Loader loader(*scene, defines, abs.parent_path().string(), unused);
    loader.finish(loader.parseFile(abs.string(), path));
    scene->setWarnings(unused.warnings());
    return scene;
}

}  // namespace pf
