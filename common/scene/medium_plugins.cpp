// The participating-medium plugins of Mitsuba 0.6 that pathfarm supports. Heterogeneous (grid) media
// are not among them yet.
#include "medium/media.h"

namespace pf {

PluginTable mediumPlugins() {
    return {
        {"homogeneous", createHomogeneousMedium},
    };
}

}  // namespace pf
