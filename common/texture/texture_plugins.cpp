// The texture plugins of Mitsuba 0.6 that pathfarm supports. Constant values need no plugin: the loader
// wraps spectrum and float parameters in a ConstantTexture (Properties::getTexture).
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createBitmapTexture(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createCheckerboardTexture(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createScaleTexture(const Properties &props, const LoadContext &ctx);

PluginTable texturePlugins() {
    return {
        {"bitmap", createBitmapTexture},
        {"checkerboard", createCheckerboardTexture},
        {"scale", createScaleTexture},
    };
}

}  // namespace pf
