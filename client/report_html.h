// index.html of a comparison: a self-contained page (no scripts, no network resources; the PNGs it
// shows lie beside it) with the protocol, side-by-side images with their crops and error maps, the
// metrics table (mean ± spread over repetitions) and the log-log convergence plot.
#pragma once
#include <string>

#include "compare_report.h"

namespace pf::client {

std::string reportHtml(const CompareReport &report);

}  // namespace pf::client
