#include "scene/properties.h"

#include <algorithm>
#include <cmath>

#include "texture/texture.h"

namespace pf {

namespace {

const char *typeName(Properties::Type t) {
    switch (t) {
        case Properties::Type::Boolean:
            return "boolean";
        case Properties::Type::Integer:
            return "integer";
        case Properties::Type::Float:
            return "float";
        case Properties::Type::String:
            return "string";
        case Properties::Type::Spectrum:
            return "spectrum";
        case Properties::Type::Point:
            return "point";
        case Properties::Type::Vector:
            return "vector";
        case Properties::Type::Transform:
            return "transform";
    }
    return "value";
}

// Which stored types a getter of type `expected` accepts. Mitsuba 0.6 promotes integers to floats and
// floats to grey spectra (Properties::getSpectrum); points and vectors are both plain triples in the
// XML, so either is accepted where the other is asked for.
bool accepts(Properties::Type expected, Properties::Type stored) {
    using T = Properties::Type;
    if (expected == stored) return true;
    switch (expected) {
        case T::Float:
            return stored == T::Integer;
        case T::Spectrum:
            return stored == T::Integer || stored == T::Float;
        case T::Point:
            return stored == T::Vector;
        case T::Vector:
            return stored == T::Point;
        default:
            return false;
    }
}

double asDouble(const Properties::Value &v) {
    if (const auto *i = std::get_if<int64_t>(&v)) return static_cast<double>(*i);
    return std::get<double>(v);
}

}  // namespace

void Properties::set(const std::string &name, Type type, Value value, const SourceLocation &loc) {
    if (has(name)) {
        throw SceneError(loc, "duplicate parameter '" + name + "' (first set on line " +
                                  std::to_string(values_.at(name).loc.line) + ")");
    }
    values_.emplace(name, Entry{type, std::move(value), loc});
}

Properties::Type Properties::type(const std::string &name) const {
    const auto it = values_.find(name);
    if (it == values_.end()) fail("missing parameter '" + name + "'");
    return it->second.type;
}

SourceLocation Properties::locationOf(const std::string &name) const {
    const auto it = values_.find(name);
    return it == values_.end() ? loc_ : it->second.loc;
}

const Properties::Entry *Properties::find(const std::string &name, Type expected) const {
    const auto it = values_.find(name);
    if (it == values_.end()) return nullptr;
    const Entry &e = it->second;
    e.used = true;
    if (!accepts(expected, e.type)) {
        fail(name, std::string("expected a ") + typeName(expected) + " value but got a " + typeName(e.type));
    }
    return &e;
}

bool Properties::getBool(const std::string &name) const {
    const Entry *e = find(name, Type::Boolean);
    if (!e) fail("missing parameter '" + name + "'");
    return std::get<bool>(e->value);
}

bool Properties::getBool(const std::string &name, bool def) const {
    const Entry *e = find(name, Type::Boolean);
    return e ? std::get<bool>(e->value) : def;
}

int64_t Properties::getInt(const std::string &name) const {
    const Entry *e = find(name, Type::Integer);
    if (!e) fail("missing parameter '" + name + "'");
    return std::get<int64_t>(e->value);
}

int64_t Properties::getInt(const std::string &name, int64_t def) const {
    const Entry *e = find(name, Type::Integer);
    return e ? std::get<int64_t>(e->value) : def;
}

double Properties::getFloat(const std::string &name) const {
    const Entry *e = find(name, Type::Float);
    if (!e) fail("missing parameter '" + name + "'");
    const double v = asDouble(e->value);
    if (!std::isfinite(v)) fail(name, "value is not a finite number");
    return v;
}

double Properties::getFloat(const std::string &name, double def) const { return has(name) ? getFloat(name) : def; }

std::string Properties::getString(const std::string &name) const {
    const Entry *e = find(name, Type::String);
    if (!e) fail("missing parameter '" + name + "'");
    return std::get<std::string>(e->value);
}

std::string Properties::getString(const std::string &name, const std::string &def) const {
    const Entry *e = find(name, Type::String);
    return e ? std::get<std::string>(e->value) : def;
}

Spectrum Properties::getSpectrum(const std::string &name) const {
    const Entry *e = find(name, Type::Spectrum);
    if (!e) fail("missing parameter '" + name + "'");
    const Spectrum s = e->type == Type::Spectrum ? std::get<Spectrum>(e->value) : Spectrum(asDouble(e->value));
    if (!s.isFinite()) fail(name, "spectrum has a non-finite component");
    return s;
}

Spectrum Properties::getSpectrum(const std::string &name, const Spectrum &def) const {
    return has(name) ? getSpectrum(name) : def;
}

Vec3 Properties::getPoint(const std::string &name) const {
    const Entry *e = find(name, Type::Point);
    if (!e) fail("missing parameter '" + name + "'");
    return std::get<Vec3>(e->value);
}

Vec3 Properties::getPoint(const std::string &name, const Vec3 &def) const { return has(name) ? getPoint(name) : def; }

Vec3 Properties::getVector(const std::string &name) const {
    const Entry *e = find(name, Type::Vector);
    if (!e) fail("missing parameter '" + name + "'");
    return std::get<Vec3>(e->value);
}

Vec3 Properties::getVector(const std::string &name, const Vec3 &def) const { return has(name) ? getVector(name) : def; }

Transform Properties::getTransform(const std::string &name) const {
    const Entry *e = find(name, Type::Transform);
    if (!e) fail("missing parameter '" + name + "'");
    return std::get<Transform>(e->value);
}

Transform Properties::getTransform(const std::string &name, const Transform &def) const {
    return has(name) ? getTransform(name) : def;
}

std::vector<std::shared_ptr<Object>> Properties::children(ObjectKind kind) const {
    std::vector<std::shared_ptr<Object>> out;
    for (const Child &c : children_) {
        if (c.kind != kind) continue;
        c.used = true;
        out.push_back(c.object);
    }
    return out;
}

std::shared_ptr<Object> Properties::child(ObjectKind kind, const std::string &name) const {
    for (const Child &c : children_) {
        if (c.kind == kind && c.name == name) {
            c.used = true;
            return c.object;
        }
    }
    return nullptr;
}

std::shared_ptr<Texture> Properties::getTexture(const std::string &name, const Spectrum &def) const {
    if (auto obj = child(ObjectKind::Texture, name)) return std::static_pointer_cast<Texture>(obj);
    return std::make_shared<ConstantTexture>(getSpectrum(name, def));
}

std::shared_ptr<Texture> Properties::getTexture(const std::string &name) const {
    if (auto obj = child(ObjectKind::Texture, name)) return std::static_pointer_cast<Texture>(obj);
    return std::make_shared<ConstantTexture>(getSpectrum(name));
}

void Properties::checkUsed(UnusedParameters &unused) const {
    // In file order, so that under --strict the error is the first leftover a reader scanning the element
    // would find, and the warnings read top to bottom.
    struct Leftover {
        const SourceLocation *loc;
        const std::string *name;  // a parameter; nullptr for a child
        const Child *child;
    };
    std::vector<Leftover> leftovers;
    for (const auto &[name, e] : values_)
        if (!e.used) leftovers.push_back({&e.loc, &name, nullptr});
    for (const Child &c : children_)
        if (!c.used) leftovers.push_back({&c.loc, nullptr, &c});
    std::stable_sort(leftovers.begin(), leftovers.end(),
                     [](const Leftover &a, const Leftover &b) { return a.loc->line < b.loc->line; });
    for (const Leftover &l : leftovers) {
        if (l.name) {
            unused.report(*l.loc, pluginName_, *l.name);
            continue;
        }
        // Mitsuba 0.6 refuses a child that a plugin does not take (ConfigurableObject::addChild).
        const Child &c = *l.child;
        throw SceneError(*l.loc, pluginName_ + ": cannot use the nested <" + objectKindName(c.kind) + ">" +
                                     (c.name.empty() ? "" : " named '" + c.name + "'") +
                                     (c.object->id().empty() ? "" : " (id '" + c.object->id() + "')"));
    }
}

void Properties::checkAllUsed() const {
    UnusedParameters strict(true);
    checkUsed(strict);
}

void Properties::fail(const std::string &name, const std::string &msg) const {
    throw SceneError(locationOf(name), pluginName_ + ": parameter '" + name + "': " + msg);
}

void Properties::fail(const std::string &msg) const { throw SceneError(loc_, pluginName_ + ": " + msg); }

}  // namespace pf
