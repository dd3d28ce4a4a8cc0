// Mitsuba 0.6's rectangle: the square [-1, 1]^2 in the z = 0 plane with normal +z and texture
// coordinates [0, 1]^2, as a two-triangle mesh under `toWorld`; with `portal` set, a portal of the portal
// perturbation instead (scene/portal.h), which is not geometry.
#include "scene/plugins.h"
#include "scene/portal.h"
#include "shape/trianglemesh.h"

namespace pf {

std::shared_ptr<Object> createRectangle(const Properties &props, const LoadContext &) {
    if (props.getBool("portal", false)) return Portal::fromProperties(props);
    MeshData d;
    d.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    d.normals.assign(4, Vec3(0, 0, 1));
    d.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    d.triangles = {{0, 1, 2}, {2, 3, 0}};
    return std::make_shared<TriangleMesh>(props, std::move(d), MeshOptions::fromProperties(props),
                                          props.location().str());
}

}  // namespace pf
