#include "farm/convert.h"

#include <algorithm>
#include <cctype>

namespace pf::farm {

namespace {

// JOB_RUNNING -> running: the generated name without its prefix, in lowercase.
std::string shorten(std::string name, const std::string &prefix) {
    if (name.rfind(prefix, 0) == 0) name.erase(0, prefix.size());
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
    return name.empty() ? "unknown" : name;
}

}  // namespace

std::string stateName(pathfarm::v1::JobState s) { return shorten(pathfarm::v1::JobState_Name(s), "JOB_"); }

std::string stateName(pathfarm::v1::WorkerState s) { return shorten(pathfarm::v1::WorkerState_Name(s), "WORKER_"); }

std::string describeWork(const pathfarm::v1::TaskSpec &work) {
    if (work.has_seeding())
        return "seeding pixels [" + std::to_string(work.seeding().first_pixel()) + ", " +
               std::to_string(work.seeding().first_pixel() + work.seeding().pixel_count()) + ")";
    if (work.has_chain())
        return "chain task " + std::to_string(work.chain().index()) + ", " +
               std::to_string(work.chain().seeds().pixel_size()) + " chains of " +
               std::to_string(work.chain().mutations()) + " mutations";
    return std::string(work.image().direct() ? "direct component, " : "") + "samples [" +
           std::to_string(work.image().first_sample()) + ", " +
           std::to_string(work.image().first_sample() + work.image().sample_count()) + ")" +
           (work.image().tiles() > 0 ? " in the first " + std::to_string(work.image().tiles()) + " tiles" : "");
}

NameValues toNameValues(const google::protobuf::RepeatedPtrField<pathfarm::v1::Param> &params) {
    NameValues out;
    for (const auto &p : params) out.emplace_back(p.name(), p.value());
    return out;
}

}  // namespace pf::farm
