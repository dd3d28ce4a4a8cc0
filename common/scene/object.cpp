#include "scene/object.h"

namespace pf {

// The element names of Mitsuba 0.6's XML schema, so that messages quote what the user wrote.
const char *objectKindName(ObjectKind kind) {
    switch (kind) {
        case ObjectKind::Scene:
            return "scene";
        case ObjectKind::Shape:
            return "shape";
        case ObjectKind::BSDF:
            return "bsdf";
        case ObjectKind::Texture:
            return "texture";
        case ObjectKind::Emitter:
            return "emitter";
        case ObjectKind::Sensor:
            return "sensor";
        case ObjectKind::Film:
            return "film";
        case ObjectKind::RFilter:
            return "rfilter";
        case ObjectKind::Sampler:
            return "sampler";
        case ObjectKind::Integrator:
            return "integrator";
        case ObjectKind::Medium:
            return "medium";
        case ObjectKind::Phase:
            return "phase";
    }
    return "object";
}

}  // namespace pf
