// The emitter plugins of Mitsuba 0.6 that pathfarm supports: all of them.
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createAreaEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createPointEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createSpotEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createDirectionalEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createConstantEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createEnvMapEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createSkyEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createSunEmitter(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createSunSkyEmitter(const Properties &props, const LoadContext &ctx);

PluginTable emitterPlugins() {
    return {
        {"area", createAreaEmitter},         {"point", createPointEmitter},
        {"spot", createSpotEmitter},         {"directional", createDirectionalEmitter},
        {"constant", createConstantEmitter}, {"envmap", createEnvMapEmitter},
        {"sky", createSkyEmitter},           {"sun", createSunEmitter},
        {"sunsky", createSunSkyEmitter},
    };
}

}  // namespace pf
