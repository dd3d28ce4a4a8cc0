// Mitsuba 0.6's "perspective" sensor: an ideal pinhole camera. Parameters (as in Mitsuba): toWorld
// (rotation and translation only), fov in degrees with fovAxis (x, y, diagonal, smaller, larger; default
// x), or alternatively focalLength as a 35 mm equivalent ("50mm", the default), nearClip (1e-2) and
// farClip (1e4), plus a nested film (default hdrfilm) and sampler (default 4 samples per pixel). The
// aperture is a point, so its position is a Discrete measure and no path can hit it.
#include "sensor/projective.h"

namespace pf {

std::shared_ptr<Object> createPerspectiveSensor(const Properties &props, const LoadContext &ctx) {
    return std::make_shared<ProjectiveCamera>(props, ctx);
}

}  // namespace pf
