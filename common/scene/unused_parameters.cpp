#include "scene/unused_parameters.h"

namespace pf {

void UnusedParameters::report(const SourceLocation &loc, const std::string &plugin, const std::string &name) {
    // The strict message is the one pathfarm always gave, so scripts matching it keep working.
    if (strict_) throw SceneError(loc, plugin + ": unknown parameter '" + name + "'");
    warnings_.push_back({loc, plugin + ": unused parameter '" + name + "'"});
}

}  // namespace pf
