// Where the sun stands for a date, a local time and a place on Earth: the PSA algorithm of Blanco-Muriel,
// Alarcon-Padilla, Lopez-Moratalla and Lara-Coira, "Computing the Solar Vector", Solar Energy 70(5),
// 431-441, 2001, which Mitsuba 0.6 uses for its sun and sky. Its stated accuracy is 0.5 arc minutes
// (0.0083 degrees) over 1999-2015; it models neither atmospheric refraction nor daylight-saving time.
#pragma once
#include "emitter/sunsky/horizon_frame.h"

namespace pf::sunsky {

struct DateTimeLocation {
    int year = 2010, month = 7, day = 10;      // civil date (Gregorian)
    double hour = 15, minute = 0, second = 0;  // local time
    double latitude = 35.6894;                 // degrees north
    double longitude = 139.6917;               // degrees east
    double timezone = 9;                       // hours east of UTC
};

// The sun's topocentric zenith angle (with the parallax of the Earth's radius, no refraction) and azimuth
// (from north towards east), in the frame of horizon_frame.h.
SphericalCoordinates solarPosition(const DateTimeLocation &when);

}  // namespace pf::sunsky
