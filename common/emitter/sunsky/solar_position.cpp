#include "emitter/sunsky/solar_position.h"

#include <cmath>

namespace pf::sunsky {

// Blanco-Muriel et al. 2001, the PSA algorithm step by step. Angles in radians, times in days from
// the J2000.0 epoch (JD 2451545.0).
SphericalCoordinates solarPosition(const DateTimeLocation &when) {
    // Universal time in decimal hours.
    const double decimalHours = when.hour - when.timezone + (when.minute + when.second / 60.0) / 60.0;

    // Julian day of the civil date (Fliegel & Van Flandern 1968); the integer divisions truncate towards
    // zero, as in the paper's C code.
    const long month = when.month, year = when.year, day = when.day;
    const long a1 = (month - 14) / 12;
    const long a2 = (1461 * (year + 4800 + a1)) / 4 + (367 * (month - 2 - 12 * a1)) / 12 -
                    (3 * ((year + 4900 + a1) / 100)) / 4 + day - 32075;
    const double julianDate = static_cast<double>(a2) - 0.5 + decimalHours / 24.0;
    const double n = julianDate - 2451545.0;

    // Ecliptic coordinates of the sun: longitude of the ascending node of the Moon's orbit (for the
    // nutation terms), mean longitude, mean anomaly, ecliptic longitude and obliquity of the ecliptic.
    const double omega = 2.1429 - 0.0010394594 * n;
    const double meanLongitude = 4.8950630 + 0.017202791698 * n;
    const double meanAnomaly = 6.2400600 + 0.0172019699 * n;
    const double eclipticLongitude = meanLongitude + 0.03341607 * std::sin(meanAnomaly) +
                                     0.00034894 * std::sin(2.0 * meanAnomaly) - 0.0001134 - 0.0000203 * std::sin(omega);
    const double obliquity = 0.4090928 - 6.2140e-9 * n + 0.0000396 * std::cos(omega);

    // Celestial coordinates: right ascension and declination.
    const double sinLambda = std::sin(eclipticLongitude);
    double rightAscension = std::atan2(std::cos(obliquity) * sinLambda, std::cos(eclipticLongitude));
    if (rightAscension < 0) rightAscension += 2.0 * kPi;
    const double declination = std::asin(std::sin(obliquity) * sinLambda);

    // Local coordinates: Greenwich and local mean sidereal time, hour angle, then zenith and azimuth.
    const double gmst = 6.6974243242 + 0.0657098283 * n + decimalHours;
    const double lmst = degToRad(gmst * 15.0 + when.longitude);
    const double hourAngle = lmst - rightAscension;
    const double latitude = degToRad(when.latitude);
    const double cosLatitude = std::cos(latitude), sinLatitude = std::sin(latitude);
    const double cosHourAngle = std::cos(hourAngle);

    SphericalCoordinates sun;
    sun.theta = safeAcos(cosLatitude * cosHourAngle * std::cos(declination) + std::sin(declination) * sinLatitude);
    sun.phi = std::atan2(-std::sin(hourAngle), std::tan(declination) * cosLatitude - sinLatitude * cosHourAngle);
    if (sun.phi < 0) sun.phi += 2.0 * kPi;

    // Parallax: the observer sits on the Earth's surface, not at its centre (mean radius 6371.01 km, one
    // astronomical unit 149597890 km).
    constexpr double kEarthMeanRadius = 6371.01, kAstronomicalUnit = 149597890.0;
    sun.theta += kEarthMeanRadius / kAstronomicalUnit * std::sin(sun.theta);
    return sun;
}

}  // namespace pf::sunsky
