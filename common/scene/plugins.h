// The plugin table: maps (element kind, type attribute) to a factory. Each plugin's .cpp defines its
// factory function; plugins.cpp lists them all in one place, so the set of supported Mitsuba plugins
// is visible at a glance (and no static-initialization tricks are needed).
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "scene/object.h"
#include "scene/properties.h"

namespace pf {

// Context passed to factories: the directory that relative file names resolve against, and the
// file-resolver rules (scene bundles may not escape their root).
struct LoadContext {
    std::string sceneDir;  // directory of the file being parsed
    std::string rootDir;   // directory of the top-level scene file
    // Resolves a file name parameter relative to sceneDir; throws SceneError (at the parameter's line)
    // if the file does not exist.
    std::string resolve(const Properties &props, const std::string &paramName) const;
};

using PluginFactory = std::function<std::shared_ptr<Object>(const Properties &, const LoadContext &)>;

// Per-category tables, each defined next to the plugins it lists (e.g. bsdf/bsdf_plugins.cpp).
using PluginTable = std::vector<std::pair<std::string, PluginFactory>>;
PluginTable shapePlugins();     // shape/shape_plugins.cpp
PluginTable bsdfPlugins();      // bsdf/bsdf_plugins.cpp
PluginTable texturePlugins();   // texture/texture_plugins.cpp
PluginTable emitterPlugins();   // emitter/emitter_plugins.cpp
PluginTable sensorPlugins();    // sensor/sensor_plugins.cpp
PluginTable filmPlugins();      // image/film_plugins.cpp (hdrfilm, ldrfilm)
PluginTable rfilterPlugins();   // image/film_plugins.cpp (box, tent, gaussian)
PluginTable samplerPlugins();   // scene/sampler_settings.cpp (independent, stratified, sobol, ...)
PluginTable mediumPlugins();    // scene/medium_plugins.cpp (homogeneous)
PluginTable phasePlugins();     // medium/phase_plugins.cpp (isotropic, hg)

// Returns nullptr if no such plugin exists.
const PluginFactory *findPlugin(ObjectKind kind, const std::string &type);
// Names of all plugins of a kind (for "unknown plugin" error messages).
std::vector<std::string> pluginNames(ObjectKind kind);

}  // namespace pf
