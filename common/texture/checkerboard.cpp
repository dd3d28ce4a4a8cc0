// Mitsuba 0.6's checkerboard texture (src/textures/checkerboard.cpp): color0 (default 0.4) and color1
// (default 0.2) alternate on squares of side 1/2 in the transformed uv.
#include <cmath>

#include "scene/plugins.h"
#include "texture/texture.h"

namespace pf {

namespace {

class Checkerboard final : public Texture {
public:
    explicit Checkerboard(const Properties &props)
        : map_(props),
          color0_(props.getSpectrum("color0", Spectrum(0.4))),
          color1_(props.getSpectrum("color1", Spectrum(0.2))) {}

    // Mitsuba indexes the squares with (int)(2u), which truncates towards zero, so the two squares
    // either side of u = 0 are the same colour; kept for identical renders of Mitsuba scenes.
    Spectrum eval(const Intersection &its) const override {
        const Vec2 uv = map_.apply(its.uv);
        return oddSquare(uv.x) == oddSquare(uv.y) ? color0_ : color1_;
    }
    Spectrum average() const override { return (color0_ + color1_) * 0.5; }
    Spectrum maximum() const override {
        return {std::max(color0_.r, color1_.r), std::max(color0_.g, color1_.g), std::max(color0_.b, color1_.b)};
    }

private:
    // fmod of the truncated value avoids the int overflow Mitsuba's cast has for large coordinates.
    static bool oddSquare(double x) { return std::fmod(std::trunc(2.0 * x), 2.0) != 0.0; }

    UVMapping map_;
    Spectrum color0_, color1_;
};

}  // namespace

std::shared_ptr<Object> createCheckerboardTexture(const Properties &props, const LoadContext &) {
    return std::make_shared<Checkerboard>(props);
}

}  // namespace pf
