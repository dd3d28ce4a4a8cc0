#include "shape/shapegroup.h"

#include <stdexcept>

#include "scene/plugins.h"
#include "shape/instance.h"

namespace pf {

ShapeGroup::ShapeGroup(const Properties &props) {
    for (const auto &child : props.children(ObjectKind::Shape)) {
        auto shape = std::dynamic_pointer_cast<Shape>(child);
        // Mitsuba 0.6 neither nests instancing nor instances emitters.
        if (dynamic_cast<const ShapeGroup *>(shape.get()) || dynamic_cast<const Instance *>(shape.get()))
            throw SceneError(child->location(), "shapegroup: shape groups and instances cannot be nested");
        if (!dynamic_cast<const Instanceable *>(shape.get()))
            throw SceneError(child->location(), "shapegroup: this shape cannot be instanced");
        if (shape->emitter()) throw SceneError(child->location(), "shapegroup: instanced shapes cannot be emitters");
        bbox_.expand(shape->bbox());
        shapes_.push_back(std::move(shape));
    }
    if (shapes_.empty()) props.fail("a shapegroup needs at least one shape");
}

unsigned ShapeGroup::addToEmbree(RTCDevice, RTCScene) const {
    throw std::logic_error("a shapegroup is rendered through its instances only");
}
void ShapeGroup::fillIntersection(const Ray &, double, uint32_t, const Vec2 &, Intersection &) const {
    throw std::logic_error("a shapegroup is rendered through its instances only");
}
void ShapeGroup::samplePosition(PositionSample &, const Vec2 &) const {
    throw std::logic_error("a shapegroup has no surface of its own");
}

std::shared_ptr<Object> createShapeGroup(const Properties &props, const LoadContext &) {
    return std::make_shared<ShapeGroup>(props);
}

}  // namespace pf
