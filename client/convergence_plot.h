// Log-log convergence plots (error against time) as inline SVG for the comparison report: no script,
// no external resources, so the page works offline and in a headless browser.
#pragma once
#include <string>
#include <utility>
#include <vector>

namespace pf::client {

struct PlotSeries {
    std::string label, colour;                      // colour: any SVG colour, e.g. "#1f77b4"
    std::vector<std::pair<double, double>> points;  // (x, y); points with x or y <= 0 or not finite are left out
    bool inLegend = true;                           // several series (repetitions) may share one legend entry
};

// An SVG element of `width` x `height` pixels: decade grid lines and labels on both axes, one polyline
// with markers per series, a legend. Axis ranges are whole decades around the data.
std::string logLogPlotSvg(const std::vector<PlotSeries> &series, const std::string &xLabel, const std::string &yLabel,
                          int width = 720, int height = 420);

// A colour per index, distinguishable and readable on white.
std::string seriesColour(size_t index);

}  // namespace pf::client
