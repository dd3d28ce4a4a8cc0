// Helpers shared by the BSDF plugins: lobe masks, delta-direction matching and the validated texture
// parameters of Mitsuba 0.6's BSDFs.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "bsdf/bsdf.h"
#include "scene/properties.h"
#include "texture/texture.h"

namespace pf {

// Two unit directions count as the same delta direction when their cosine is within this of 1 (an
// angle of about 4.5e-4 radians): loose enough for directions that went through world space and back
// in double precision, tight enough that no smooth-lobe direction is mistaken for the delta one.
constexpr double kDeltaEpsilon = 1e-7;

inline bool hasLobe(const BSDFContext &ctx, uint32_t lobe) { return (ctx.typeMask & lobe) != 0; }
inline bool sameDirection(const Vec3 &a, const Vec3 &b) { return std::abs(dot(a, b) - 1.0) < kDeltaEpsilon; }
inline bool isMirrorPair(const Vec3 &wi, const Vec3 &wo) { return sameDirection(reflect(wi), wo); }
inline bool isPassThrough(const Vec3 &wi, const Vec3 &wo) { return sameDirection(-wi, wo); }

inline uint32_t variationFlag(const Texture &t) { return t.isConstant() ? 0u : BSDFFlags::SpatiallyVarying; }

// Whether a parameter was given, as a value or as a nested texture of that name.
inline bool hasParameter(const Properties &props, const std::string &name) {
    return props.has(name) || props.child(ObjectKind::Texture, name) != nullptr;
}

// A reflectance or transmittance parameter (spectrum, float or nested texture, Mitsuba's getTexture
// idiom) of an energy-conserving model: it must lie in [0, 1]. Constant values are checked
// completely; textures by their maximum.
std::shared_ptr<Texture> readUnitTexture(const Properties &props, const std::string &name, const Spectrum &def);

// Nested BSDF children of an adapter plugin (twosided, mask, bumpmap), checked for count.
std::vector<std::shared_ptr<BSDF>> nestedBSDFs(const Properties &props, size_t minCount, size_t maxCount);

}  // namespace pf
