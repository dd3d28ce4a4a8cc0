#include "farm/job_setup.h"

#include <cstdlib>

namespace pf {

NameValues parseNameValues(const std::vector<std::string> &args, const std::string &flag) {
    NameValues out;
    for (const std::string &a : args) {
        const auto eq = a.find('=');
        if (eq == std::string::npos || eq == 0) throw SceneError(flag + " " + a + ": expected name=value");
        out.emplace_back(a.substr(0, eq), a.substr(eq + 1));
    }
    return out;
}

namespace {

void applyParams(Properties &props, const NameValues &params) {
    for (const auto &[name, value] : params) {
        const SourceLocation loc{"command line (-P " + name + "=" + value + ")", 0};
        props.remove(name);
        char *end = nullptr;
        if (value == "true" || value == "false") {
            props.set(name, Properties::Type::Boolean, value == "true", loc);
        } else if (const long long i = std::strtoll(value.c_str(), &end, 10); !value.empty() && *end == '\0') {
            props.set(name, Properties::Type::Integer, static_cast<int64_t>(i), loc);
        } else if (const double d = std::strtod(value.c_str(), &end); !value.empty() && *end == '\0') {
            props.set(name, Properties::Type::Float, d, loc);
        } else {
            props.set(name, Properties::Type::String, value, loc);
        }
    }
}

}  // namespace

std::unique_ptr<Integrator> makeIntegrator(const Scene &scene, const std::string &requested, const NameValues &params,
                                           bool strict, std::vector<SceneWarning> *warnings) {
    const Properties &fileProps = scene.integratorProperties();
    const std::string fileType = fileProps.pluginName().empty() ? "path" : fileProps.pluginName();
    const std::string type = requested.empty() ? fileType : requested;
    Properties props = type == fileType ? fileProps : Properties(ObjectKind::Integrator, type, {});
    // Every integrator understands maxDepth and rrDepth (Mitsuba's names and meaning), so these carry over
    // when the command line picks another integrator than the file; the rest is the file's own business.
    if (type != fileType)
        for (const char *shared : {"maxDepth", "rrDepth"})
            if (fileProps.has(shared))
                props.set(shared, fileProps.type(shared), fileProps.value(shared), fileProps.locationOf(shared));
    applyParams(props, params);
    auto integrator = createIntegrator(type, props, false);
    integrator->checkScene(scene);
    UnusedParameters unused(strict);
    props.checkUsed(unused);
    if (warnings) warnings->insert(warnings->end(), unused.warnings().begin(), unused.warnings().end());
    return integrator;
}

}  // namespace pf
