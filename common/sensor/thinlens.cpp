// Mitsuba 0.6's "thinlens" sensor: the perspective camera with a circular thin lens of radius
// apertureRadius (required) focused at focusDistance (default farClip, as in Mitsuba), which gives depth
// of field. Aperture positions are uniform on the lens disk (Measure::Area), so light paths can also end
// on the lens (the t = 0 strategy of BDPT).
#include "sensor/projective.h"

namespace pf {

namespace {

class ThinLensCamera final : public ProjectiveCamera {
public:
    ThinLensCamera(const Properties &props, const LoadContext &ctx) : ProjectiveCamera(props, ctx) {
        const double radius = props.getFloat("apertureRadius");
        if (!(radius > 0)) props.fail("apertureRadius", "must be positive (use the perspective sensor for a pinhole)");
        const double focus = props.getFloat("focusDistance", farClip());
        if (!(focus > 0)) props.fail("focusDistance", "must be positive");
        setThinLens(radius, focus);
    }
};

}  // namespace

std::shared_ptr<Object> createThinLensSensor(const Properties &props, const LoadContext &ctx) {
    return std::make_shared<ThinLensCamera>(props, ctx);
}

}  // namespace pf
