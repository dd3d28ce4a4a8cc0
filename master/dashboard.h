// The master's dashboard: one static HTML page that polls the JSON API (/api/v1/jobs, /api/v1/workers)
// and shows the jobs (state, integrator, progress, samples or mutations, rate, acceptance, elapsed time),
// the workers, and a live preview of the running image that reloads as results merge.
#pragma once
#include <string_view>

namespace pf::master {

// The page's layout pins the preview frame (tests/test_farm_dashboard.cpp finds it there in a screenshot):
// a square of kPreviewFramePx pixels whose top edge is kPreviewFrameTopPx below the top of the window and
// whose right edge is kPreviewFrameRightPx left of the window's right edge.
inline constexpr int kPreviewFramePx = 360;
inline constexpr int kPreviewFrameTopPx = 72;
inline constexpr int kPreviewFrameRightPx = 24;

std::string_view dashboardPage();

}  // namespace pf::master
