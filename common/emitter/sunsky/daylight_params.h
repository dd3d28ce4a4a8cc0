// The parameters Mitsuba 0.6's `sun`, `sky` and `sunsky` share, with its names and defaults
// (data/sunsky/MITSUBA_USAGE.md §8), and the sun they describe.
#pragma once
#include <memory>
#include <optional>

#include "core/transform.h"
#include "emitter/emitter.h"
#include "emitter/sunsky/sky_model.h"
#include "emitter/sunsky/sun_disk.h"
#include "scene/properties.h"

namespace pf::sunsky {

// The sun's position in the local frame: `sunDirection` (a world-space vector towards the sun, taken
// through toWorld's inverse), or else the date, local time and place (year, month, day, hour, minute,
// second, latitude, longitude, timezone) through the solar position algorithm.
SphericalCoordinates readSunPosition(const Properties &props, const Transform &toWorld);

// turbidity in [1, 10] (default 3) and stretch in [1, 2] (default 1).
double readTurbidity(const Properties &props);
double readStretch(const Properties &props);
// The width of the sky map in pixels (its height is half of it); default 512.
int readResolution(const Properties &props);

// Everything the sky model needs except its scale; fails if the sun is below the horizon (the model has
// no data there).
SkyParameters readSkyParameters(const Properties &props, const SphericalCoordinates &sun);

// The sun seen through the atmosphere for `sunsky` and `sun`: the solar disk of radiance
// sunRadiance(zenith, turbidity) * scale, placed at zenith angle zenith * stretch, widened by
// sunRadiusScale (default 1) at constant irradiance. sunRadiusScale = 0 gives instead a directional
// emitter of that irradiance (world space, samplingWeight from props).
struct Sun {
    std::optional<SunDisk> disk;
    std::shared_ptr<Emitter> directional;
};
Sun readSun(const Properties &props, const Transform &toWorld, const SphericalCoordinates &position, double turbidity,
            double stretch, double scale);

}  // namespace pf::sunsky
