// The sensor plugins of Mitsuba 0.6 that pathfarm supports.
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createPerspectiveSensor(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createThinLensSensor(const Properties &props, const LoadContext &ctx);

PluginTable sensorPlugins() {
    return {
        {"perspective", createPerspectiveSensor},
        {"thinlens", createThinLensSensor},
    };
}

}  // namespace pf
