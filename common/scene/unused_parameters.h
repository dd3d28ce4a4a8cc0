// What happens to a parameter that no plugin asked for. Mitsuba 0.6 logs "Unqueried attribute" as a
// warning and renders on (SceneHandler::endElement), and many published scenes carry such leftovers
// (a perspective sensor's focusDistance, say); pathfarm does the same by default. Under --strict the
// warning is the error it used to be, for users who want typos caught. Malformed values, wrong types,
// NaN and out-of-range values are always errors: Mitsuba refuses those too.
#pragma once
#include <string>
#include <vector>

#include "core/error.h"

namespace pf {

// "scene.xml:17: perspective: unused parameter 'focusDistance'"; the CLI prefixes "warning: ".
struct SceneWarning {
    SourceLocation loc;
    std::string message;
    std::string str() const { return loc.file.empty() ? message : loc.str() + ": " + message; }
};

class UnusedParameters {
public:
    explicit UnusedParameters(bool strict) : strict_(strict) {}
    bool strict() const { return strict_; }
    // Strict: throws SceneError(loc, "<plugin>: unknown parameter 'name'"). Otherwise records a warning.
    void report(const SourceLocation &loc, const std::string &plugin, const std::string &name);
    const std::vector<SceneWarning> &warnings() const { return warnings_; }

private:
    bool strict_;
    std::vector<SceneWarning> warnings_;
};

}  // namespace pf
