#include <functional>
#include <map>

#include "integrators/bdpt.h"
#include "integrators/erpt.h"
#include "integrators/integrator.h"
#include "integrators/mlt.h"
#include "integrators/mmlt.h"
#include "integrators/path.h"
#include "integrators/pssmlt.h"
#include "integrators/sms_connection.h"

namespace pf {

namespace {

using Factory = std::function<std::unique_ptr<Integrator>(const Properties &)>;

const std::map<std::string, Factory> &factories() {
    static const std::map<std::string, Factory> table = {
        {"bdpt", [](const Properties &p) { return std::make_unique<BDPT>(p); }},
        {"erpt", [](const Properties &p) { return std::make_unique<ERPT>(p); }},
        {"memlt", [](const Properties &p) { return std::make_unique<MLT>(p, true); }},
        {"mept", [](const Properties &p) { return std::make_unique<ERPT>(p, true); }},
        {"mlt", [](const Properties &p) { return std::make_unique<MLT>(p); }},
        {"mmlt", [](const Properties &p) { return std::make_unique<MMLT>(p); }},
        {"path", [](const Properties &p) { return std::make_unique<PathTracer>(p, false); }},
        {"pssmlt", [](const Properties &p) { return std::make_unique<PSSMLT>(p); }},
        {"sms",
         [](const Properties &p) {
             return std::make_unique<PathTracer>(p, false, std::make_shared<SmsConnection>(p));
         }},
        {"volpath", [](const Properties &p) { return std::make_unique<PathTracer>(p, true); }},
    };
    return table;
}

}  // namespace

std::string integratorNames() {
    std::string names;
    for (const auto &[name, f] : factories()) names += (names.empty() ? "" : ", ") + name;
    return names;
}

std::unique_ptr<Integrator> createIntegrator(const std::string &type, const Properties &props, bool strict) {
    const auto it = factories().find(type);
    if (it == factories().end())
        throw SceneError(props.location(), "unknown integrator '" + type + "' (available: " + integratorNames() + ")");
    auto integrator = it->second(props);
    if (strict) props.checkAllUsed();
    return integrator;
}

}  // namespace pf
