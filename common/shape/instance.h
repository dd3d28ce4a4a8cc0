// Mitsuba 0.6's instance plugin: a shapegroup placed under a toWorld transform, flattened into
// transformed copies of the group's shapes (see shape/shapegroup.h for why).
#pragma once
#include <memory>
#include <vector>

#include "core/distribution.h"
#include "scene/shape.h"

namespace pf {

class Properties;

// One placement of a shapegroup.
class Instance final : public Shape {
public:
    explicit Instance(const Properties &props);
    // The group's shapes under this instance's transform, ready to be added to a scene.
    const std::vector<std::shared_ptr<Shape>> &parts() const { return parts_; }

    unsigned addToEmbree(RTCDevice device, RTCScene scene) const override;
    void fillIntersection(const Ray &ray, double t, uint32_t primIndex, const Vec2 &embreeUV,
                          Intersection &its) const override;
    AABB bbox() const override { return bbox_; }
    double surfaceArea() const override { return area_; }
    size_t primitiveCount() const override;
    // Uniform by area over all parts.
    void samplePosition(PositionSample &ps, const Vec2 &u) const override;

private:
    std::vector<std::shared_ptr<Shape>> parts_;
    Distribution1D partAreas_;
    AABB bbox_;
    double area_ = 0;
};

}  // namespace pf
