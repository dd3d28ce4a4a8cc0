// Named indices of refraction, as accepted by Mitsuba 0.6 scenes: the dielectric table of
// src/bsdfs/ior.h (intIOR / extIOR / extEta may be a number or one of these names) and the conductor
// presets of the conductor / roughconductor "material" parameter, converted to linear sRGB.
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "core/spectrum.h"
#include "scene/properties.h"

namespace pf {

// Case-insensitive lookup in Mitsuba's dielectric table ("vacuum", "air", "water", "bk7", ...).
std::optional<double> lookupDielectricIOR(const std::string &name);
std::vector<std::string> dielectricIORNames();

// Reads a dielectric IOR parameter given either as a positive number or as a table name; the default
// is a table name (Mitsuba's lookupIOR(props, name, default)). Fails naming the parameter otherwise.
double readDielectricIOR(const Properties &props, const std::string &name, const std::string &defaultName);

struct ConductorIOR {
    Spectrum eta, k;
};
// Case-insensitive lookup of a conductor preset ("Ag", "Al", "Au", "Cu", "Cr", ..., and "none", a
// perfect mirror with eta = 0, k = 1).
std::optional<ConductorIOR> lookupConductorIOR(const std::string &name);
std::vector<std::string> conductorIORNames();

// The conductor parameters of Mitsuba 0.6 (material, default "Cu"; eta and k overriding it; extEta,
// default "air"), returned relative to the exterior medium as Mitsuba does (eta / extEta, k / extEta).
ConductorIOR readConductorIOR(const Properties &props);

}  // namespace pf
