// The numeric tables of the daylight emitters, compiled in (tables.cpp is generated from data/sunsky/ by
// scripts/gen_sunsky_tables.py; data/sunsky/README.md gives their layout, units and provenance).
#pragma once

namespace pf::sunsky {

// Hosek-Wilkie RGB sky model (Hosek & Wilkie 2012, reference code version 1.2). Per channel: 2 albedos x
// 10 turbidities x 6 Bezier control points x 9 parameters, and 2 x 10 x 6 radiance control points.
extern const double kHosekRGBCoeffs[3240];
extern const double kHosekRGBRadiance[360];

// Sun tables (Iqbal 1983 via Preetham et al. 1999): absorption coefficients of ozone, uniformly mixed gases
// and water vapour in 1/cm, and the extraterrestrial solar spectral radiance in W m^-2 sr^-1 nm^-1, each
// against wavelength in nm.
extern const double kSunKOWavelengths[64], kSunKOValues[64];
extern const double kSunKGWavelengths[4], kSunKGValues[4];
extern const double kSunKWaWavelengths[13], kSunKWaValues[13];
extern const double kSunSolarWavelengths[38], kSunSolarValues[38];

}  // namespace pf::sunsky
