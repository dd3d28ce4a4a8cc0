// Turning a job description (scene, integrator name, -P parameters, -D definitions) into a loaded scene and
// an integrator. `pathfarm render`, the master (which validates submitted jobs) and the workers all go
// through these functions, so that a job means the same thing wherever it runs.
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "integrators/integrator.h"
#include "scene/scene.h"

namespace pf {

using NameValues = std::vector<std::pair<std::string, std::string>>;

// Splits "name=value" arguments of the command-line flag `flag` (-D, -P); throws SceneError naming the
// argument when one has no '=' or an empty name.
NameValues parseNameValues(const std::vector<std::string> &args, const std::string &flag);

// The integrator a job uses: `requested` ("" = the scene file's, which defaults to "path"). The file's
// parameters are checked when they were written for this integrator; when another one is requested, the
// parameters shared by every integrator (maxDepth, rrDepth, ...) carry over and the rest is ignored.
// `params` replace the file's values, typed like the scene file would type them (boolean, integer,
// float, else string). Throws SceneError for unknown integrators or bad parameters. A parameter (from the
// file or -P) that the integrator does not use is an error when `strict`, else a warning appended to
// `warnings` (dropped when null), as the scene loader does for every other plugin.
std::unique_ptr<Integrator> makeIntegrator(const Scene &scene, const std::string &requested, const NameValues &params,
                                           bool strict = false, std::vector<SceneWarning> *warnings = nullptr);

}  // namespace pf
