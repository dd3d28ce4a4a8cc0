#include "emitter/sunsky/daylight_params.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "emitter/directional.h"
#include "emitter/sunsky/solar_position.h"
#include "emitter/sunsky/sun_radiance.h"

namespace pf::sunsky {

namespace {

std::string degrees(double radians) {
    std::ostringstream os;
    os << std::setprecision(4) << radToDeg(radians) << " degrees";
    return os.str();
}

double floatInRange(const Properties &props, const std::string &name, double def, double lo, double hi,
                    const char *range) {
    const double v = props.getFloat(name, def);
    if (!(v >= lo && v <= hi)) props.fail(name, std::string("must be in ") + range);
    return v;
}

}  // namespace

SphericalCoordinates readSunPosition(const Properties &props, const Transform &toWorld) {
    if (props.has("sunDirection")) {
        // As in Mitsuba: a direction and a time or place contradict each other.
        for (const char *name : {"latitude", "longitude", "timezone", "day", "time"})
            if (props.has(name))
                props.fail("sunDirection", std::string("cannot be combined with '") + name +
                                               "' (give either a direction or a date, time and place)");
        const Vec3 d = toWorld.inverse().vector(props.getVector("sunDirection"));
        if (!(d.length() > 0)) props.fail("sunDirection", "must be a non-zero vector");
        return fromSphere(normalize(d));
    }
    DateTimeLocation when;
    // The Julian-day formula of solar_position.cpp holds from 4713 BC on; the bound also keeps its integer
    // arithmetic far from overflow.
    const int64_t year = props.getInt("year", when.year);
    if (year < -4700 || year > 100000) props.fail("year", "must be in -4700..100000");
    when.year = static_cast<int>(year);
    when.month = static_cast<int>(props.getInt("month", when.month));
    when.day = static_cast<int>(props.getInt("day", when.day));
    if (when.month < 1 || when.month > 12) props.fail("month", "must be in 1..12");
    if (when.day < 1 || when.day > 31) props.fail("day", "must be in 1..31");
    when.hour = props.getFloat("hour", when.hour);
    when.minute = props.getFloat("minute", when.minute);
    when.second = props.getFloat("second", when.second);
    when.latitude = floatInRange(props, "latitude", when.latitude, -90, 90, "[-90, 90]");
    when.longitude = props.getFloat("longitude", when.longitude);
    when.timezone = props.getFloat("timezone", when.timezone);
    return solarPosition(when);
}

double readTurbidity(const Properties &props) { return floatInRange(props, "turbidity", 3.0, 1.0, 10.0, "[1, 10]"); }
double readStretch(const Properties &props) { return floatInRange(props, "stretch", 1.0, 1.0, 2.0, "[1, 2]"); }

int readResolution(const Properties &props) {
    const int64_t r = props.getInt("resolution", 512);
    if (r < 2 || r > 65536) props.fail("resolution", "must be in 2..65536");
    return static_cast<int>(r);
}

SkyParameters readSkyParameters(const Properties &props, const SphericalCoordinates &sun) {
    SkyParameters p;
    p.sun = sun;
    p.turbidity = readTurbidity(props);
    p.stretch = readStretch(props);
    p.albedo = props.getSpectrum("albedo", p.albedo);
    if (!(p.albedo.min() >= 0 && p.albedo.max() <= 1)) props.fail("albedo", "must be in [0, 1]");
    p.extend = props.getBool("extend", false);
    if (sun.theta > 0.5 * kPi)
        props.fail("the sun is below the horizon (zenith angle " + degrees(sun.theta) +
                   "), where the Hosek-Wilkie sky model has no data");
    return p;
}

Sun readSun(const Properties &props, const Transform &toWorld, const SphericalCoordinates &position, double turbidity,
            double stretch, double scale) {
    const double radiusScale = props.getFloat("sunRadiusScale", 1.0);
    const double halfAngle = degToRad(kSunHalfAngleDegrees);
    if (!(radiusScale >= 0 && halfAngle * radiusScale <= kPi))
        props.fail("sunRadiusScale", "must be non-negative, and the disk no wider than the sphere");
    // Kasten's air mass, and with it the attenuation, breaks down 3.885 degrees below the horizon.
    const Spectrum radiance = sunRadiance(position.theta, turbidity) * scale;
    if (!radiance.isValid())
        props.fail("the sun is too far below the horizon (zenith angle " + degrees(position.theta) +
                   ") for its attenuation to be defined");
    // The irradiance is that of the real disk whatever sunRadiusScale: a larger disk is only dimmer.
    const Spectrum irradiance = radiance * coneSolidAngle(halfAngle);
    const Vec3 direction = toSphere({position.theta * stretch, position.phi});
    Sun sun;
    if (radiusScale == 0)
        sun.directional =
            makeDirectionalEmitter(-toWorld.vector(direction), irradiance, props.getFloat("samplingWeight", 1.0));
    else
        sun.disk = SunDisk(direction, halfAngle * radiusScale, irradiance);
    return sun;
}

}  // namespace pf::sunsky
