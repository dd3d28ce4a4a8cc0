// A ray-surface intersection with full local differential geometry. Manifold exploration
// (ALGORITHMS.md §6.2) needs dp/du, dp/dv, dn/du and dn/dv at every vertex; all shapes fill them and
// tests/test_shapes.cpp checks them against finite differences. Meshes leave dn/du and dn/dv out of a hit
// (normalDerivativesPending) until Shape::fillNormalDerivatives: nothing but the manifold code reads them,
// and on every other hit they cost about a third of the mesh's differential geometry (issue 17's profile).
#pragma once
#include <cstdint>

#include "core/frame.h"
#include "core/spectrum.h"

namespace pf {

class Shape;
class BSDF;
class Emitter;
class Medium;

struct Intersection {
    double t = kInfinity;  // ray distance
    Vec3 p;                // position
    Vec3 n;                // geometric normal, unit length, as oriented by the shape (never flipped to the ray)
    Frame shFrame;         // shading frame; shFrame.n is the shading normal (same hemisphere as n)
    Vec2 uv;               // surface parameterization
    Vec3 dpdu, dpdv;       // position partials
    Vec3 dndu, dndv;       // shading-normal partials (of the normalized shading normal); see above
    Vec3 wi;               // incident direction (towards the ray origin) in the local shading frame
    const Shape *shape = nullptr;
    uint32_t primIndex = 0;
    Vec2 primUV;                            // the hit's coordinates on primitive primIndex (a mesh's b1, b2)
    bool normalDerivativesPending = false;  // dndu, dndv not computed yet (Shape::fillNormalDerivatives)
    // Instance transform applied to the shape, if any, is already folded into all the above.

    bool isValid() const { return shape != nullptr; }
    Vec3 toWorld(const Vec3 &v) const { return shFrame.toWorld(v); }
    Vec3 toLocal(const Vec3 &v) const { return shFrame.toLocal(v); }

    // Convenience accessors resolved through the shape. bsdf() is inline in scene/shape.h: Markov chains ask
    // for a vertex's BSDF many times per step (issue 17).
    inline const BSDF *bsdf() const;
    const Emitter *emitter() const;
    bool isEmitter() const { return emitter() != nullptr; }
    // Emitted radiance towards world direction d (zero for non-emitters).
    Spectrum Le(const Vec3 &d) const;
    // Medium on the side of the surface that direction d points into (nullptr = vacuum).
    const Medium *targetMedium(const Vec3 &d) const;
};

}  // namespace pf
