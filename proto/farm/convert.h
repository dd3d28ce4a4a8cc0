// Between proto messages and the words of logs, listings and the renderer.
#pragma once
#include <string>

#include "farm/job_setup.h"
#include "pathfarm/v1/common.pb.h"

namespace pf::farm {

// Short lowercase names of the proto enums ("running", "lost") for logs, listings and metrics labels.
std::string stateName(pathfarm::v1::JobState s);
std::string stateName(pathfarm::v1::WorkerState s);

// What a task does, for logs: "samples [0, 8)", "samples [5, 6) in the first 460 tiles", "direct component,
// samples [0, 8)", "seeding pixels [0, 4096)", "chain task 3, 1 chains of 16384 mutations".
std::string describeWork(const pathfarm::v1::TaskSpec &work);

// A job's parameters or definitions as the renderer takes them.
NameValues toNameValues(const google::protobuf::RepeatedPtrField<pathfarm::v1::Param> &params);

}  // namespace pf::farm
