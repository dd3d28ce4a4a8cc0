#include "scene/intersection.h"

#include "emitter/emitter.h"
#include "scene/shape.h"

namespace pf {

const Emitter *Intersection::emitter() const { return shape ? shape->emitter() : nullptr; }

Spectrum Intersection::Le(const Vec3 &d) const {
    const Emitter *e = emitter();
    return e ? e->eval(*this, d) : Spectrum(0.0);
}

// The exterior lies on the side the (shape-oriented) geometric normal points to.
const Medium *Intersection::targetMedium(const Vec3 &d) const {
    if (!shape) return nullptr;
    return dot(d, n) > 0 ? shape->exteriorMedium() : shape->interiorMedium();
}

}  // namespace pf
