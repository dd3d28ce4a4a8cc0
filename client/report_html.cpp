#include "report_html.h"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "convergence_plot.h"
#include "markup.h"

namespace pf::client {

namespace {

std::string fmt(const char *format, double v) {
    char b[64];
    std::snprintf(b, sizeof b, format, v);
    return b;
}

std::string meanSpread(const Spread &s, int runs, const char *format = "%.4g") {
    std::string out = fmt(format, s.mean);
    if (runs > 1) out += " ± " + fmt("%.2g", s.stddev);
    return out;
}

// Images are shown at least 256 pixels wide (small test renders are enlarged without smoothing) and at
// most 400, side by side.
int displayWidth(int width) { return width < 256 ? 256 : std::min(width, 400); }

std::string figure(const std::string &png, const std::string &caption, int width, const std::string &overlay = "") {
    std::ostringstream o;
    o << "<figure><div class=\"frame\" style=\"width:" << width << "px\"><img src=\"" << escapeMarkup(png)
      << "\" alt=\"" << escapeMarkup(caption) << "\" width=\"" << width << "\">" << overlay << "</div><figcaption>"
      << escapeMarkup(caption) << "</figcaption></figure>\n";
    return o.str();
}

const RunResult *firstRun(const CompareReport &r, const std::string &integrator) {
    for (const RunResult &run : r.runs)
        if (run.integrator == integrator) return &run;
    return nullptr;
}

void protocol(std::ostringstream &o, const CompareReport &r) {
    o << "<section id=\"protocol\"><h2>Protocol</h2><ul>\n";
    o << "<li>Scene <code>" << escapeMarkup(r.scene) << "</code> (bundle " << escapeMarkup(r.bundleHash) << "), "
      << r.width << "×" << r.height << " pixels";
    for (const auto &[n, v] : r.defines) o << ", <code>-D " << escapeMarkup(n + "=" + v) << "</code>";
    for (const auto &[n, v] : r.params) o << ", <code>-P " << escapeMarkup(n + "=" + v) << "</code>";
    o << ".</li>\n<li>Equal time: every run has a budget of " << fmt("%g", r.timeBudget)
      << " s on the same workers, one job at a time; the budget decides how many whole tasks are issued, and the "
         "true render time (first lease to last merge) is reported. "
      << r.repeat << " repetition(s); repetition k uses seed " << r.seed << " + k.</li>\n";
    o << "<li>Farm: " << (r.embeddedFarm ? "embedded (loopback master and worker on this machine)" : "master ")
      << (r.embeddedFarm ? "" : escapeMarkup(r.master)) << "; workers:";
    for (const WorkerSummary &w : r.workers)
        o << " " << escapeMarkup(w.name) << " (" << w.threads << " threads of " << w.cores << " cores)";
    o << ".</li>\n<li>Reference: ";
    if (r.reference.source == "file")
        o << "<code>" << escapeMarkup(r.reference.exr) << "</code> (given).";
    else
        o << escapeMarkup(r.reference.integrator) << ", " << r.reference.spp << " spp, rendered on the farm in "
          << fmt("%.1f", r.reference.renderSeconds) << " s"
          << (r.reference.source == "cache" ? " (from the cache " : " (cached as ") << "<code>"
          << escapeMarkup(r.reference.cacheFile) << "</code>).";
    o << "</li>\n<li>Metrics, with a the rendered value and b the reference's:<ul>\n";
    for (const Metric m : allMetrics())
        o << "<li>" << metricName(m) << ": " << escapeMarkup(metricDefinition(m, r.metricOptions.epsilon)) << "</li>\n";
    o << "<li>efficiency: 1 / (relMSE × render seconds)</li></ul>epsilon = " << fmt("%g", r.metricOptions.epsilon)
      << "; trim: "
      << (r.metricOptions.trimFraction > 0 ? "the highest " + fmt("%g", 100 * r.metricOptions.trimFraction) +
                                                 "% of per-pixel errors are discarded from each metric"
                                           : std::string("none (every pixel counts)"))
      << ".</li>\n<li>Images: tonemapped to sRGB with one exposure, " << fmt("%+.2f", r.exposure)
      << " stops, for all. Error maps: per-pixel relMSE, black 0 to yellow " << fmt("%.3g", r.errorMapMax)
      << " and above.</li>\n</ul></section>\n";
}

void images(std::ostringstream &o, const CompareReport &r) {
    const int w = displayWidth(r.width);
    // The crop regions, outlined on the reference.
    std::string overlay;
    for (size_t i = 0; i < r.crops.size(); ++i) {
        const CropRegion &c = r.crops[i];
        overlay += "<div class=\"region\" style=\"left:" + fmt("%.3f", 100.0 * c.x / r.width) +
                   "%;top:" + fmt("%.3f", 100.0 * c.y / r.height) + "%;width:" + fmt("%.3f", 100.0 * c.size / r.width) +
                   "%;height:" + fmt("%.3f", 100.0 * c.size / r.height) + "%\"><span>" + std::to_string(i + 1) +
                   "</span></div>";
    }
    o << "<section id=\"images\"><h2>Images (repetition 0)</h2><div class=\"row\">\n";
    o << figure(r.reference.png, "reference", w, overlay);
    for (const std::string &integrator : r.integrators)
        if (const RunResult *run = firstRun(r, integrator))
            o << figure(
                run->png,
                integrator + ", " + std::to_string(run->spp) + " spp, " + fmt("%.2f", run->renderSeconds) + " s", w);
    o << "</div>\n<h3>Error maps (per-pixel relMSE)</h3><div class=\"row\">\n";
    o << "<figure><div class=\"frame\" style=\"width:" << w << "px\"></div></figure>\n";
    for (const std::string &integrator : r.integrators)
        if (const RunResult *run = firstRun(r, integrator))
            o << figure(run->errorPng, integrator + ": relMSE " + fmt("%.3g", run->metrics.relMse), w);
    o << "</div></section>\n<section id=\"crops\"><h2>Zoomed regions</h2>\n";
    for (size_t i = 0; i < r.crops.size(); ++i) {
        const CropRegion &c = r.crops[i];
        o << "<h3>Region " << i + 1 << ": pixels (" << c.x << ", " << c.y << ") to (" << c.x + c.size << ", "
          << c.y + c.size << ")</h3><div class=\"row\">\n";
        for (const auto &[name, png] : c.pngs) o << figure(png, name, 192);
        o << "</div>\n";
    }
    o << "</section>\n";
}

void table(std::ostringstream &o, const CompareReport &r) {
    o << "<section id=\"metrics\"><h2>Error metrics (mean ± standard deviation over repetitions)</h2>\n"
         "<table id=\"metrics-table\"><thead><tr><th>algorithm</th><th>runs</th><th>spp</th><th>render s</th>"
         "<th>scene load s</th>";
    for (const Metric m : allMetrics()) o << "<th>" << metricName(m) << "</th>";
    o << "<th>efficiency</th></tr></thead><tbody>\n";
    for (const IntegratorSummary &s : summarize(r)) {
        o << "<tr><td>" << escapeMarkup(s.integrator) << "</td><td>" << s.runs << "</td><td>"
          << meanSpread(s.get("spp"), s.runs, "%.1f") << "</td><td>"
          << meanSpread(s.get("renderSeconds"), s.runs, "%.2f") << "</td><td>"
          << meanSpread(s.get("sceneLoadSeconds"), s.runs, "%.3f") << "</td>";
        for (const Metric m : allMetrics()) o << "<td>" << meanSpread(s.get(metricName(m)), s.runs) << "</td>";
        o << "<td>" << meanSpread(s.get("efficiency"), s.runs) << "</td></tr>\n";
    }
    o << "</tbody></table>\n<details><summary>Every run</summary><table><thead><tr><th>algorithm</th><th>rep</th>"
         "<th>seed</th><th>job</th><th>spp</th><th>render s</th><th>relmse</th><th>rmse</th><th>image</th>"
         "</tr></thead><tbody>\n";
    for (const RunResult &run : r.runs)
        o << "<tr><td>" << escapeMarkup(run.integrator) << "</td><td>" << run.repetition << "</td><td>" << run.seed
          << "</td><td>" << run.job << "</td><td>" << run.spp << "</td><td>" << fmt("%.2f", run.renderSeconds)
          << "</td><td>" << fmt("%.4g", run.metrics.relMse) << "</td><td>" << fmt("%.4g", run.metrics.rmse)
          << "</td><td><a href=\"" << escapeMarkup(run.exr) << "\">" << escapeMarkup(run.exr) << "</a></td></tr>\n";
    o << "</tbody></table></details></section>\n";
}

void convergence(std::ostringstream &o, const CompareReport &r) {
    std::vector<PlotSeries> series;
    for (size_t i = 0; i < r.integrators.size(); ++i)
        for (const RunResult &run : r.runs) {
            if (run.integrator != r.integrators[i]) continue;
            PlotSeries s{run.integrator, seriesColour(i), {}, run.repetition == 0};
            for (const SnapshotResult &snap : run.snapshots) s.points.emplace_back(snap.seconds, snap.metrics.relMse);
            s.points.emplace_back(run.renderSeconds, run.metrics.relMse);
            series.push_back(std::move(s));
        }
    o << "<section id=\"convergence\"><h2>Convergence: relMSE against render time (log-log)</h2>\n"
      << "<p>One line per run, from snapshots of the running image fetched from the master during the job; the "
         "last point is the final image. An unbiased method's relMSE falls as 1/time (slope -1).</p>\n"
      << logLogPlotSvg(series, "render time (s)", "relMSE") << "</section>\n";
}

}  // namespace

std::string reportHtml(const CompareReport &r) {
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>pathfarm compare: "
      << escapeMarkup(r.scene)
      << "</title>\n<style>\n"
         "body{font-family:sans-serif;margin:1.5em;color:#222;background:#fff}"
         "h1{font-size:1.5em}h2{font-size:1.2em;margin-top:1.5em}"
         ".row{display:flex;flex-wrap:wrap;gap:12px}figure{margin:0}"
         "figcaption{font-size:.85em;text-align:center;margin-top:4px}"
         ".frame{position:relative;line-height:0}.frame img{image-rendering:pixelated;display:block}"
         ".region{position:absolute;border:2px solid #0f0;box-sizing:border-box}"
         ".region span{position:absolute;left:2px;top:8px;color:#0f0;font-size:11px}"
         "table{border-collapse:collapse;font-size:.9em}td,th{border:1px solid #bbb;padding:3px 8px;"
         "text-align:right}td:first-child,th:first-child{text-align:left}th{background:#eee}\n"
         "</style></head><body>\n<h1>pathfarm compare: "
      << escapeMarkup(r.scene) << "</h1>\n";
    protocol(o, r);
    table(o, r);
    convergence(o, r);
    images(o, r);
    o << "<p>All numbers: <a href=\"report.json\">report.json</a>.</p>\n</body></html>\n";
    return o.str();
}

}  // namespace pf::client
