// The shape plugins (Mitsuba 0.6 names and parameters).
#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createObj(const Properties &, const LoadContext &);
std::shared_ptr<Object> createPly(const Properties &, const LoadContext &);
std::shared_ptr<Object> createSerialized(const Properties &, const LoadContext &);
std::shared_ptr<Object> createRectangle(const Properties &, const LoadContext &);
std::shared_ptr<Object> createCube(const Properties &, const LoadContext &);
std::shared_ptr<Object> createDisk(const Properties &, const LoadContext &);
std::shared_ptr<Object> createSphere(const Properties &, const LoadContext &);
std::shared_ptr<Object> createCylinder(const Properties &, const LoadContext &);
std::shared_ptr<Object> createShapeGroup(const Properties &, const LoadContext &);
std::shared_ptr<Object> createInstance(const Properties &, const LoadContext &);

PluginTable shapePlugins() {
    return {
        {"obj", createObj},
        {"ply", createPly},
        {"serialized", createSerialized},
        {"rectangle", createRectangle},
        {"cube", createCube},
        {"disk", createDisk},
        {"sphere", createSphere},
        {"cylinder", createCylinder},
        {"shapegroup", createShapeGroup},
        {"instance", createInstance},
    };
}

}  // namespace pf
