// A latitude-longitude environment image with its importance sampling: what the envmap emitter loads from
// a file and what the sky emitter rasterizes. Orientation as in Mitsuba 0.6: a local direction v maps to
// u = atan2(v.x, -v.z) / (2 pi) (wrapped into [0, 1)) and v = acos(v.y) / pi, so +y is up, the image's top
// row is the zenith, and its horizontal centre looks along +z. Each pixel is a constant-radiance patch (no
// interpolation), which makes the map that is seen exactly the map that is sampled.
//
// Importance sampling (pbrt-v3 §14.2.4): a piecewise-constant 2D distribution over (u, v) with weights
// luminance * sin(theta at the row centre); the solid-angle density is p(u, v) / (2 pi^2 sin theta).
#pragma once
#include "core/distribution.h"
#include "core/spectrum.h"
#include "core/vector.h"
#include "image/bitmap.h"

namespace pf {

class LatLongMap {
public:
    LatLongMap() = default;
    // Throws std::invalid_argument if the image is empty, has negative or non-finite pixels, or is black
    // (there would be nothing to sample).
    explicit LatLongMap(Bitmap map);

    // Radiance seen looking along unit vector v.
    Spectrum eval(const Vec3 &v) const;
    // A direction drawn in proportion to luminance, with its solid-angle density.
    Vec3 sample(const Vec2 &u, double &pdf) const;
    double pdf(const Vec3 &v) const;
    // Exact integral of the piecewise-constant map over the sphere of directions.
    Spectrum integral() const;
    const Bitmap &bitmap() const { return map_; }

private:
    int column(double u) const { return std::min(static_cast<int>(u * map_.width), map_.width - 1); }
    int row(double v) const { return std::min(static_cast<int>(v * map_.height), map_.height - 1); }

    Bitmap map_;
    Distribution2D dist_;
};

}  // namespace pf
