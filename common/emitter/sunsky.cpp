// Mitsuba 0.6's `sunsky` emitter: the `sky` and the `sun` of one sun position and turbidity together, the
// sky scaled by skyScale and the sun by sunScale (both default to scale). The sky map and the solar disk
// form one environment emitter; with sunRadiusScale = 0 the sun is a directional emitter beside the sky,
// as Mitsuba builds it.
#include <initializer_list>
#include <utility>

#include "emitter/endpoint.h"
#include "emitter/sunsky/daylight_emitter.h"
#include "emitter/sunsky/daylight_params.h"
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createSunSkyEmitter(const Properties &props, const LoadContext &) {
    const Transform toWorld = rigidTransform(props, "toWorld");
    const sunsky::SphericalCoordinates position = sunsky::readSunPosition(props, toWorld);
    const double scale = props.getFloat("scale", 1.0);
    const double skyScale = props.getFloat("skyScale", scale), sunScale = props.getFloat("sunScale", scale);
    for (const auto &[name, value] : std::initializer_list<std::pair<const char *, double>>{
             {"scale", scale}, {"skyScale", skyScale}, {"sunScale", sunScale}})
        if (!(value >= 0)) props.fail(name, "must be non-negative");
    if (!(skyScale > 0 || sunScale > 0)) props.fail("scale", "the sun and the sky cannot both be black");

    sunsky::SkyParameters sky = sunsky::readSkyParameters(props, position);
    sky.scale = skyScale;
    const int resolution = sunsky::readResolution(props);
    sunsky::Sun sun = sunsky::readSun(props, toWorld, position, sky.turbidity, sky.stretch, sunScale);

    std::optional<LatLongMap> skyMap;
    if (skyScale > 0) skyMap = LatLongMap(sunsky::SkyModel(sky).rasterize(resolution));
    if (sunScale == 0) sun.disk.reset();
    if (!skyMap && !sun.disk) return sun.directional;  // a black sky beside a directional sun
    auto emitter = std::make_shared<sunsky::DaylightEmitter>(props, toWorld, std::move(skyMap), sun.disk);
    if (sun.directional && sunScale > 0) emitter->addCompanion(sun.directional);
    return emitter;
}

}  // namespace pf
