// Base class of every scene plugin (shape, bsdf, texture, emitter, sensor, film, rfilter, medium ...).
#pragma once
#include <memory>
#include <string>

#include "core/error.h"

namespace pf {

// The XML element name a plugin was declared with; also used to check <ref> targets.
enum class ObjectKind { Scene, Shape, BSDF, Texture, Emitter, Sensor, Film, RFilter, Sampler, Integrator, Medium, Phase };

const char *objectKindName(ObjectKind kind);

class Object {
public:
    virtual ~Object() = default;
    const std::string &id() const { return id_; }
    const SourceLocation &location() const { return loc_; }
    void setIdentity(const std::string &id, const SourceLocation &loc) { id_ = id; loc_ = loc; }

private:
    std::string id_;
    SourceLocation loc_;
};

}  // namespace pf
