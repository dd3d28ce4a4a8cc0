// Parameters of one plugin instance as written in the scene file (Mitsuba's Properties). Every getter
// marks the parameter as used; after construction the loader calls checkUsed(), so a misspelt or
// unknown parameter is a warning (an error under --strict) that names the parameter, the plugin and the
// line, and a nested object the plugin cannot take is an error (as Mitsuba's addChild).
#pragma once
#include <map>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "core/error.h"
#include "core/spectrum.h"
#include "core/transform.h"
#include "scene/object.h"
#include "scene/unused_parameters.h"

namespace pf {

class Texture;

class Properties {
public:
    enum class Type { Boolean, Integer, Float, String, Spectrum, Point, Vector, Transform };
    using Value = std::variant<bool, int64_t, double, std::string, Spectrum, Vec3, Transform>;

    Properties() = default;
    Properties(ObjectKind kind, std::string pluginName, SourceLocation loc)
        : kind_(kind), pluginName_(std::move(pluginName)), loc_(std::move(loc)) {}

    ObjectKind kind() const { return kind_; }
    const std::string &pluginName() const { return pluginName_; }
    const std::string &id() const { return id_; }
    void setId(const std::string &id) { id_ = id; }
    const SourceLocation &location() const { return loc_; }

    // Throws SceneError if the name is already set (Mitsuba rejects duplicate parameters).
    void set(const std::string &name, Type type, Value value, const SourceLocation &loc);
    bool has(const std::string &name) const { return values_.count(name) != 0; }
    // Raw value of a parameter (throws if absent), for copying parameters between plugin descriptions.
    const Value &value(const std::string &name) const {
        const auto it = values_.find(name);
        if (it == values_.end()) fail(name, "missing parameter");
        return it->second.value;
    }
    // Drops a parameter (so that a command-line override can replace it with set()).
    void remove(const std::string &name) { values_.erase(name); }
    // Type of a parameter; throws if absent.
    Type type(const std::string &name) const;
    // Location of a parameter (falls back to the plugin's location).
    SourceLocation locationOf(const std::string &name) const;

    // Getters without a default throw SceneError("missing parameter") when absent; all throw on a type
    // mismatch. Integers are accepted where floats are expected. getFloat rejects NaN and infinities.
    bool getBool(const std::string &name) const;
    bool getBool(const std::string &name, bool def) const;
    int64_t getInt(const std::string &name) const;
    int64_t getInt(const std::string &name, int64_t def) const;
    double getFloat(const std::string &name) const;
    double getFloat(const std::string &name, double def) const;
    std::string getString(const std::string &name) const;
    std::string getString(const std::string &name, const std::string &def) const;
    // A float parameter is promoted to a grey spectrum. Rejects NaN/inf components.
    Spectrum getSpectrum(const std::string &name) const;
    Spectrum getSpectrum(const std::string &name, const Spectrum &def) const;
    Vec3 getPoint(const std::string &name) const;
    Vec3 getPoint(const std::string &name, const Vec3 &def) const;
    Vec3 getVector(const std::string &name) const;
    Vec3 getVector(const std::string &name, const Vec3 &def) const;
    Transform getTransform(const std::string &name) const;
    Transform getTransform(const std::string &name, const Transform &def) const;

    // Nested objects (inline children and <ref>s). The name is the child's name attribute ("" if none).
    struct Child {
        std::string name;
        ObjectKind kind;
        std::shared_ptr<Object> object;
        SourceLocation loc;
        mutable bool used = false;
    };
    void addChild(Child child) { children_.push_back(std::move(child)); }
    // All children of a kind, marking them used.
    std::vector<std::shared_ptr<Object>> children(ObjectKind kind) const;
    // Named child of a kind (nullptr if absent), marking it used.
    std::shared_ptr<Object> child(ObjectKind kind, const std::string &name) const;
    // A texture-valued parameter: a named child texture, or a spectrum/float parameter of that name
    // (wrapped in a constant texture), or the default. (Mitsuba's getTexture idiom.)
    std::shared_ptr<Texture> getTexture(const std::string &name, const Spectrum &def) const;
    std::shared_ptr<Texture> getTexture(const std::string &name) const;

    // Goes through the parameters and children that no getter asked for, in file order: an unused
    // parameter goes to `unused` (a warning, or an error when strict); an unused child is an error.
    void checkUsed(UnusedParameters &unused) const;
    // checkUsed() with a strict sink: throws SceneError naming the first unused parameter or child.
    void checkAllUsed() const;

    // Raise a SceneError at a parameter's location: "<plugin>: parameter 'name': msg".
    [[noreturn]] void fail(const std::string &name, const std::string &msg) const;
    // Raise a SceneError at the plugin's location.
    [[noreturn]] void fail(const std::string &msg) const;

private:
    struct Entry {
        Type type;
        Value value;
        SourceLocation loc;
        mutable bool used = false;
    };
    const Entry *find(const std::string &name, Type expected) const;

    ObjectKind kind_ = ObjectKind::Scene;
    std::string pluginName_, id_;
    SourceLocation loc_;
    std::map<std::string, Entry> values_;
    std::vector<Child> children_;
};

}  // namespace pf
