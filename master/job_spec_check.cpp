#include "job_spec_check.h"

#include <cmath>

#include "farm/error.h"

namespace pf::master {

void checkJobSpec(const JobSpec &spec, const MasterConfig &cfg) {
    constexpr int kMaxParams = 256;
    constexpr size_t kMaxText = 4096;
    if (spec.bundle_hash().empty()) throw farm::FarmError("job spec: bundle_hash is missing (upload the scene first)");
    if (spec.params_size() > kMaxParams || spec.defines_size() > kMaxParams)
        throw farm::FarmError("job spec: more than " + std::to_string(kMaxParams) + " parameters or definitions");
    for (const auto *list : {&spec.params(), &spec.defines()})
        for (const auto &p : *list)
            if (p.name().empty() || p.name().size() > kMaxText || p.value().size() > kMaxText)
                throw farm::FarmError("job spec: parameter '" + p.name().substr(0, 64) +
                                      "' has an empty or overlong name or value");
    if (spec.integrator().size() > kMaxText || spec.label().size() > kMaxText)
        throw farm::FarmError("job spec: overlong integrator name or label");
    if (spec.budget().has_spp() && (spec.budget().spp() < 1 || spec.budget().spp() > cfg.maxSpp))
        throw farm::FarmError("job spec: spp must be in [1, " + std::to_string(cfg.maxSpp) + "], got " +
                              std::to_string(spec.budget().spp()));
    if (spec.budget().has_time_seconds()) {
        const double t = spec.budget().time_seconds();
        if (!std::isfinite(t) || t <= 0 || t > cfg.maxTimeSeconds)
            throw farm::FarmError("job spec: time budget must be in (0, " + std::to_string(cfg.maxTimeSeconds) +
                                  "] seconds, got " + std::to_string(t));
    }
}

}  // namespace pf::master
