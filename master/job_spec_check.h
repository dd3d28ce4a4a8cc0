// The first check of a submitted job spec, before anything is loaded: what no scene or integrator could
// make sense of, and what exceeds this master's limits. Apart from the submission so that the decoding
// of client requests can be fuzzed (fuzz/fuzz_master_requests.cpp).
#pragma once
#include "master.h"

namespace pf::master {

// Throws farm::FarmError naming the field.
void checkJobSpec(const JobSpec &spec, const MasterConfig &cfg);

}  // namespace pf::master
