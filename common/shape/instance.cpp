#include "shape/instance.h"

#include <stdexcept>

#include "scene/plugins.h"
#include "shape/shapegroup.h"

namespace pf {

Instance::Instance(const Properties &props) {
    const Transform toWorld = props.getTransform("toWorld", Transform());
    const auto children = props.children(ObjectKind::Shape);
    const auto *group = children.size() == 1 ? dynamic_cast<const ShapeGroup *>(children[0].get()) : nullptr;
    if (!group) props.fail("an instance needs exactly one shapegroup (as a <ref>)");
    std::vector<double> areas;
    for (const auto &shape : group->shapes()) {
        parts_.push_back(dynamic_cast<const Instanceable &>(*shape).transformedCopy(toWorld, props));
        areas.push_back(parts_.back()->surfaceArea());
        bbox_.expand(parts_.back()->bbox());
    }
    partAreas_ = Distribution1D(areas);
    area_ = partAreas_.sum();
}

unsigned Instance::addToEmbree(RTCDevice, RTCScene) const {
    throw std::logic_error("an instance is added to the scene as its parts");
}
void Instance::fillIntersection(const Ray &, double, uint32_t, const Vec2 &, Intersection &) const {
    throw std::logic_error("an instance is added to the scene as its parts");
}

size_t Instance::primitiveCount() const {
    size_t n = 0;
    for (const auto &p : parts_) n += p->primitiveCount();
    return n;
}

void Instance::samplePosition(PositionSample &ps, const Vec2 &u) const {
    double ux;
    const size_t i = partAreas_.sampleDiscrete(u.x, nullptr, &ux);
    parts_[i]->samplePosition(ps, Vec2(ux, u.y));
    ps.pdf = 1.0 / area_;
}

std::shared_ptr<Object> createInstance(const Properties &props, const LoadContext &) {
    return std::make_shared<Instance>(props);
}

}  // namespace pf
