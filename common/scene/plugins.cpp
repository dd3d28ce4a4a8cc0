#include "scene/plugins.h"

#include <filesystem>
#include <map>

namespace pf {

namespace fs = std::filesystem;

namespace {

// Built once, on first use (thread-safe static initialization), from the per-category tables.
const std::map<ObjectKind, PluginTable> &pluginTables() {
    static const std::map<ObjectKind, PluginTable> tables = {
        {ObjectKind::Shape, shapePlugins()},     {ObjectKind::BSDF, bsdfPlugins()},
        {ObjectKind::Texture, texturePlugins()}, {ObjectKind::Emitter, emitterPlugins()},
        {ObjectKind::Sensor, sensorPlugins()},   {ObjectKind::Film, filmPlugins()},
        {ObjectKind::RFilter, rfilterPlugins()}, {ObjectKind::Sampler, samplerPlugins()},
        {ObjectKind::Medium, mediumPlugins()},   {ObjectKind::Phase, phasePlugins()},
    };
    return tables;
}

// True if `path` (lexically normal, absolute) equals `root` or lies below it.
bool isInside(const fs::path &path, const fs::path &root) {
    auto p = path.begin();
    for (auto r = root.begin(); r != root.end(); ++r, ++p) {
        if (r->empty()) continue;  // trailing separator of a directory path
        if (p == path.end() || *p != *r) return false;
    }
    return true;
}

}  // namespace

const PluginFactory *findPlugin(ObjectKind kind, const std::string &type) {
    const auto &tables = pluginTables();
    const auto it = tables.find(kind);
    if (it == tables.end()) return nullptr;
    for (const auto &[name, factory] : it->second)
        if (name == type) return &factory;
    return nullptr;
}

std::vector<std::string> pluginNames(ObjectKind kind) {
    std::vector<std::string> names;
    const auto &tables = pluginTables();
    const auto it = tables.find(kind);
    if (it != tables.end())
        for (const auto &entry : it->second) names.push_back(entry.first);
    return names;
}

// File names are resolved against the directory of the XML file that names them (Mitsuba 0.6 adds
// that directory to its file resolver while parsing). A scene bundle is uploaded to render workers
// as a self-contained unit, so absolute names and names that climb out of the top-level scene's
// directory are refused outright rather than silently reading the host's files.
std::string LoadContext::resolve(const Properties &props, const std::string &paramName) const {
    const std::string name = props.getString(paramName);
    if (name.empty()) props.fail(paramName, "empty file name");
    const fs::path given(name);
    if (given.has_root_path() || given.has_root_name())
        props.fail(paramName, "absolute path '" + name + "': scene bundles cannot reach outside themselves");
    const fs::path root = fs::absolute(rootDir.empty() ? fs::path(".") : fs::path(rootDir)).lexically_normal();
    const fs::path full =
        (fs::absolute(sceneDir.empty() ? fs::path(".") : fs::path(sceneDir)) / given).lexically_normal();
    if (!isInside(full, root))
        props.fail(paramName, "path '" + name +
                                  "' leaves the scene directory: scene bundles cannot reach "
                                  "outside themselves");
    std::error_code ec;
    if (!fs::is_regular_file(full, ec)) props.fail(paramName, "file '" + name + "' not found");
    return full.string();
}

}  // namespace pf
