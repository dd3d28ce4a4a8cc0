// The phase-function plugins of Mitsuba 0.6 that pathfarm supports (nested <phase> inside <medium>).
#include "medium/media.h"

namespace pf {

PluginTable phasePlugins() {
    return {
        {"isotropic", createIsotropicPhase},
        {"hg", createHGPhase},
    };
}

}  // namespace pf
