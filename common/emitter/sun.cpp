// Mitsuba 0.6's `sun` emitter: the solar disk for a date, time and place (or a sunDirection), its radiance
// the extraterrestrial spectrum attenuated by the atmosphere of the given turbidity (sunsky/sun_radiance.h).
// With sunRadiusScale = 0 it is a directional light of the disk's irradiance. Mitsuba reads `resolution`
// for the map it splats the disk into; pathfarm's disk is exact, so the parameter is accepted and unused.
#include "emitter/endpoint.h"
#include "emitter/sunsky/daylight_emitter.h"
#include "emitter/sunsky/daylight_params.h"
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createSunEmitter(const Properties &props, const LoadContext &) {
    const Transform toWorld = rigidTransform(props, "toWorld");
    const sunsky::SphericalCoordinates position = sunsky::readSunPosition(props, toWorld);
    const double scale = props.getFloat("scale", 1.0);
    if (!(scale > 0)) props.fail("scale", "must be positive");
    sunsky::readResolution(props);
    sunsky::Sun sun =
        sunsky::readSun(props, toWorld, position, sunsky::readTurbidity(props), sunsky::readStretch(props), scale);
    if (sun.directional) return sun.directional;
    return std::make_shared<sunsky::DaylightEmitter>(props, toWorld, std::nullopt, sun.disk);
}

}  // namespace pf
