// The master's figures in the Prometheus text exposition format (version 0.0.4): farm-wide gauges and
// counters from MasterMetrics, and per-job series derived from the Job messages (progress, rates, and
// for Markov-chain jobs mutation counts and acceptance ratios per mutation type).
#pragma once
#include <string>
#include <vector>

#include "master.h"

namespace pf::master {

std::string prometheusText(const MasterMetrics &metrics, const std::vector<pathfarm::v1::Job> &jobs,
                           const std::vector<pathfarm::v1::WorkerInfo> &workers);

}  // namespace pf::master
