// Textures evaluated at a surface point (uv), as Mitsuba's Texture2D: bitmap, checkerboard, scale and
// constant values.
#pragma once
#include <memory>

#include "core/spectrum.h"
#include "scene/intersection.h"
#include "scene/object.h"

namespace pf {

class Properties;

// Mitsuba's Texture2D lookup transform, shared by the uv-mapped textures: the surface's (u, v) become
// (u * uscale + uoffset, v * vscale + voffset) before the lookup.
struct UVMapping {
    Vec2 offset{0, 0}, scale{1, 1};
    UVMapping() = default;
    // Reads uoffset, voffset, uscale and vscale (defaults 0, 0, 1, 1).
    explicit UVMapping(const Properties &props);
    Vec2 apply(const Vec2 &uv) const { return {uv.x * scale.x + offset.x, uv.y * scale.y + offset.y}; }
};

class Texture : public Object {
public:
    virtual Spectrum eval(const Intersection &its) const = 0;
    // Mean value over the texture's domain (used for sampling weights, e.g. plastic's specular ratio).
    virtual Spectrum average() const = 0;
    virtual Spectrum maximum() const = 0;
    virtual bool isConstant() const { return false; }
    // Partial derivatives of eval with respect to (u, v), for bump mapping. The default uses central
    // differences in uv of size 1e-3; bitmaps override with the exact derivative of their filter.
    virtual void evalGradient(const Intersection &its, Spectrum &dfdu, Spectrum &dfdv) const;
};

class ConstantTexture final : public Texture {
public:
    explicit ConstantTexture(const Spectrum &v) : value_(v) {}
    Spectrum eval(const Intersection &) const override { return value_; }
    Spectrum average() const override { return value_; }
    Spectrum maximum() const override { return value_; }
    bool isConstant() const override { return true; }
    void evalGradient(const Intersection &, Spectrum &dfdu, Spectrum &dfdv) const override {
        dfdu = dfdv = Spectrum(0.0);
    }

private:
    Spectrum value_;
};

}  // namespace pf
