// Mitsuba 0.6's cube: [-1, 1]^3 under `toWorld`, as a mesh of 12 triangles with 4 vertices per face, so
// that every face has its own normal and texture coordinates [0, 1]^2.
#include "scene/plugins.h"
#include "shape/trianglemesh.h"

namespace pf {

std::shared_ptr<Object> createCube(const Properties &props, const LoadContext &) {
    MeshData d;
    // Each face: its outward normal n and two in-plane axes a, b with a x b = n, so that the corners
    // n + (+-a) + (+-b) in the order below wind counter-clockwise seen from outside.
    const Vec3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int axis = 0; axis < 3; ++axis)
        for (const double sign : {1.0, -1.0}) {
            const Vec3 n = axes[axis] * sign, a = axes[(axis + 1) % 3] * sign, b = cross(n, a);
            const uint32_t base = static_cast<uint32_t>(d.positions.size());
            const Vec2 corners[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
            for (const Vec2 &c : corners) {
                d.positions.push_back(n + a * (2 * c.x - 1) + b * (2 * c.y - 1));
                d.normals.push_back(n);
                d.uvs.push_back(c);
            }
            d.triangles.push_back({base, base + 1, base + 2});
            d.triangles.push_back({base + 2, base + 3, base});
        }
    return std::make_shared<TriangleMesh>(props, std::move(d), MeshOptions::fromProperties(props),
                                          props.location().str());
}

}  // namespace pf
