// Instancing (Mitsuba 0.6's shapegroup and instance plugins). A shapegroup holds shapes that are not
// rendered themselves; each instance renders the group's shapes under its own toWorld transform.
//
// Instances are flattened: every instance owns transformed copies of the group's shapes, and
// Scene::addShape adds those copies as ordinary shapes (and skips shapegroups). That costs memory for
// heavily instanced meshes, but every shape keeps its exact double-precision geometry, its own
// area-sampling table and a plain Embree geometry: no second BVH level and no ray transforms on the hot
// path. ShapeGroup and Instance (shape/instance.h) are Shapes only because the XML declares them with <shape>; the
// geometric entry points that the Scene never calls on them (addToEmbree, fillIntersection) throw std::logic_error.
#pragma once
#include <memory>
#include <vector>

#include "core/transform.h"
#include "scene/shape.h"

namespace pf {

class Properties;

// Shapes that may appear inside a shapegroup: they produce a copy of themselves with an extra transform
// applied after their own. Errors (e.g. a sphere under non-uniform scaling) are raised at `where`.
class Instanceable {
public:
    virtual ~Instanceable() = default;
    virtual std::shared_ptr<Shape> transformedCopy(const Transform &toWorld, const Properties &where) const = 0;
};

// A collection of shapes that only instances render.
class ShapeGroup final : public Shape {
public:
    explicit ShapeGroup(const Properties &props);
    const std::vector<std::shared_ptr<Shape>> &shapes() const { return shapes_; }

    unsigned addToEmbree(RTCDevice device, RTCScene scene) const override;
    void fillIntersection(const Ray &ray, double t, uint32_t primIndex, const Vec2 &embreeUV,
                          Intersection &its) const override;
    AABB bbox() const override { return bbox_; }
    // A group has no surface of its own in the scene.
    double surfaceArea() const override { return 0.0; }
    size_t primitiveCount() const override { return 0; }
    void samplePosition(PositionSample &ps, const Vec2 &u) const override;

private:
    std::vector<std::shared_ptr<Shape>> shapes_;
    AABB bbox_;
};

}  // namespace pf
