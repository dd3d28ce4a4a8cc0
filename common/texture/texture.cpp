// Shared texture machinery: Mitsuba's Texture2D uv transform (src/librender/texture.cpp) and the
// default gradient used by bump mapping.
#include "texture/texture.h"

#include "scene/properties.h"

namespace pf {

UVMapping::UVMapping(const Properties &props)
    : offset(props.getFloat("uoffset", 0.0), props.getFloat("voffset", 0.0)),
      scale(props.getFloat("uscale", 1.0), props.getFloat("vscale", 1.0)) {}

// Central differences in the surface's (u, v): second-order accurate for smooth textures, and for
// piecewise-constant ones (checkerboard) zero except within h of an edge, as a finite-difference bump
// map in Mitsuba would see it.
void Texture::evalGradient(const Intersection &its, Spectrum &dfdu, Spectrum &dfdv) const {
    constexpr double h = 1e-3;
    Intersection probe = its;
    probe.uv = Vec2(its.uv.x + h, its.uv.y);
    const Spectrum uPlus = eval(probe);
    probe.uv = Vec2(its.uv.x - h, its.uv.y);
    dfdu = (uPlus - eval(probe)) * (0.5 / h);
    probe.uv = Vec2(its.uv.x, its.uv.y + h);
    const Spectrum vPlus = eval(probe);
    probe.uv = Vec2(its.uv.x, its.uv.y - h);
    dfdv = (vPlus - eval(probe)) * (0.5 / h);
}

}  // namespace pf
