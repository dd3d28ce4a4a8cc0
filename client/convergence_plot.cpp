#include "convergence_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "markup.h"

namespace pf::client {

namespace {

std::string num(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
}

// Whole decades [lo, hi] (as exponents) covering the values, at least one decade wide.
std::pair<int, int> decades(double minValue, double maxValue) {
    int lo = static_cast<int>(std::floor(std::log10(minValue)));
    int hi = static_cast<int>(std::ceil(std::log10(maxValue)));
    if (hi <= lo) hi = lo + 1;
    return {lo, hi};
}

bool plottable(const std::pair<double, double> &p) {
    return std::isfinite(p.first) && std::isfinite(p.second) && p.first > 0 && p.second > 0;
}

}  // namespace

std::string seriesColour(size_t index) {
    static const char *const kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                           "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
    return kColours[index % (sizeof kColours / sizeof kColours[0])];
}

std::string logLogPlotSvg(const std::vector<PlotSeries> &series, const std::string &xLabel, const std::string &yLabel,
                          int width, int height) {
    double xMin = std::numeric_limits<double>::max(), xMax = 0, yMin = xMin, yMax = 0;
    for (const PlotSeries &s : series)
        for (const auto &p : s.points)
            if (plottable(p)) {
                xMin = std::min(xMin, p.first);
                xMax = std::max(xMax, p.first);
                yMin = std::min(yMin, p.second);
                yMax = std::max(yMax, p.second);
            }
    if (xMax == 0) xMin = xMax = yMin = yMax = 1;  // nothing to plot: an empty frame
    const auto [xLo, xHi] = decades(xMin, xMax);
    const auto [yLo, yHi] = decades(yMin, yMax);
    const double left = 80, right = width - 170.0, top = 20, bottom = height - 55.0;
    const auto X = [&](double x) { return left + (std::log10(x) - xLo) / (xHi - xLo) * (right - left); };
    const auto Y = [&](double y) { return bottom - (std::log10(y) - yLo) / (yHi - yLo) * (bottom - top); };

    std::ostringstream o;
    o << "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" viewBox=\"0 0 " << width << " " << height << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
    o << "<rect x=\"0\" y=\"0\" width=\"" << width << "\" height=\"" << height << "\" fill=\"white\"/>\n";
    // Grid and labels at every decade (the superscript exponent keeps labels short).
    for (int e = xLo; e <= xHi; ++e) {
        const std::string x = num(X(std::pow(10.0, e)));
        o << "<line x1=\"" << x << "\" y1=\"" << top << "\" x2=\"" << x << "\" y2=\"" << bottom
          << "\" stroke=\"#ddd\"/>\n<text x=\"" << x << "\" y=\"" << bottom + 18
          << "\" text-anchor=\"middle\">10<tspan dy=\"-6\" font-size=\"9\">" << e << "</tspan></text>\n";
    }
    for (int e = yLo; e <= yHi; ++e) {
        const std::string y = num(Y(std::pow(10.0, e)));
        o << "<line x1=\"" << left << "\" y1=\"" << y << "\" x2=\"" << right << "\" y2=\"" << y
          << "\" stroke=\"#ddd\"/>\n<text x=\"" << left - 8 << "\" y=\"" << y
          << "\" text-anchor=\"end\" dominant-baseline=\"middle\">10<tspan dy=\"-6\" font-size=\"9\">" << e
          << "</tspan></text>\n";
    }
    o << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << right - left << "\" height=\"" << bottom - top
      << "\" fill=\"none\" stroke=\"#333\"/>\n";
    o << "<text x=\"" << (left + right) / 2 << "\" y=\"" << height - 12 << "\" text-anchor=\"middle\">"
      << escapeMarkup(xLabel) << "</text>\n";
    o << "<text transform=\"translate(18," << (top + bottom) / 2 << ") rotate(-90)\" text-anchor=\"middle\">"
      << escapeMarkup(yLabel) << "</text>\n";
    int legendRow = 0;
    for (const PlotSeries &s : series) {
        std::string pts;
        o << "<g class=\"series\" data-label=\"" << escapeMarkup(s.label) << "\">";
        for (const auto &p : s.points) {
            if (!plottable(p)) continue;
            pts += num(X(p.first)) + "," + num(Y(p.second)) + " ";
            o << "<circle cx=\"" << num(X(p.first)) << "\" cy=\"" << num(Y(p.second)) << "\" r=\"2.5\" fill=\""
              << s.colour << "\"/>";
        }
        o << "<polyline points=\"" << pts << "\" fill=\"none\" stroke=\"" << s.colour
          << "\" stroke-width=\"1.5\"/></g>\n";
        if (!s.inLegend) continue;
        const double ly = top + 10 + 20 * legendRow++;
        o << "<line x1=\"" << right + 15 << "\" y1=\"" << ly << "\" x2=\"" << right + 40 << "\" y2=\"" << ly
          << "\" stroke=\"" << s.colour << "\" stroke-width=\"3\"/><text x=\"" << right + 46 << "\" y=\"" << ly
          << "\" dominant-baseline=\"middle\">" << escapeMarkup(s.label) << "</text>\n";
    }
    o << "</svg>\n";
    return o.str();
}

}  // namespace pf::client
