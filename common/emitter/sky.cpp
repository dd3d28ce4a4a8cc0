// Mitsuba 0.6's `sky` emitter: the Hosek-Wilkie clear sky for a sun position, turbidity and ground albedo,
// rasterized into a `resolution` x `resolution`/2 latitude-longitude map in the local frame of
// sunsky/horizon_frame.h and emitted as an environment map through toWorld (data/sunsky/MITSUBA_USAGE.md §4, §7).
#include "emitter/endpoint.h"
#include "emitter/sunsky/daylight_emitter.h"
#include "emitter/sunsky/daylight_params.h"
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createSkyEmitter(const Properties &props, const LoadContext &) {
    const Transform toWorld = rigidTransform(props, "toWorld");
    sunsky::SkyParameters sky = sunsky::readSkyParameters(props, sunsky::readSunPosition(props, toWorld));
    sky.scale = props.getFloat("scale", 1.0);
    if (!(sky.scale > 0)) props.fail("scale", "must be positive");
    const Bitmap map = sunsky::SkyModel(sky).rasterize(sunsky::readResolution(props));
    return std::make_shared<sunsky::DaylightEmitter>(props, toWorld, LatLongMap(map), std::nullopt);
}

}  // namespace pf
