#include "diff.h"

#include <cstdio>
#include <cstdlib>

#include "compare_report.h"
#include "core/error.h"
#include "image/bitmap.h"
#include "image/metrics.h"

namespace pf::client {

struct DiffCommand::Args {
    std::string image, reference;
    MetricOptions options;
    bool json = false;
    CLI::App *cmd = nullptr;
};

DiffCommand::DiffCommand(CLI::App &app) : a_(std::make_unique<Args>()) {
    Args &a = *a_;
    a.cmd = app.add_subcommand("diff", "Error metrics of an image against a reference (the second file)");
    a.cmd->add_option("image", a.image, "Rendered EXR")->required();
    a.cmd->add_option("reference", a.reference, "Reference EXR")->required();
    a.cmd->add_option("--trim", a.options.trimFraction, "Discard this fraction of the highest per-pixel errors")
        ->check(CLI::Range(0.0, 0.5));
    a.cmd->add_option("--epsilon", a.options.epsilon, "Epsilon in the denominators of relMSE, MAPE, SMAPE")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    a.cmd->add_flag("--json", a.json, "Print JSON instead of text");
}

DiffCommand::~DiffCommand() = default;

namespace {

// The image's mean luminance: a quick check of a whole image's brightness against the reference's (an
// unbiased render's ratio converges to 1; a missing component or a wrong normalization shows at once).
double meanLuminance(const Bitmap &b) {
    double sum = 0;
    for (int y = 0; y < b.height; ++y)
        for (int x = 0; x < b.width; ++x) sum += b.get(x, y).luminance();
    return b.width > 0 && b.height > 0 ? sum / (static_cast<double>(b.width) * b.height) : 0.0;
}

}  // namespace

int DiffCommand::run() {
    const Args &a = *a_;
    if (!*a.cmd) return -1;
    const Bitmap image = readEXR(a.image), reference = readEXR(a.reference);  // SceneError naming the file
    ErrorMetrics m;
    try {
        m = computeMetrics(image, reference, a.options);
    } catch (const MetricError &e) {
        throw SceneError(a.image + " against " + a.reference + ": " + e.what());
    }
    // The render time an EXR of `pathfarm render` or of the farm records, for the efficiency.
    const auto seconds = image.metadata.find("pathfarm.renderSeconds");
    const double renderSeconds = seconds != image.metadata.end() ? std::atof(seconds->second.c_str()) : 0.0;
    const double mean = meanLuminance(image), referenceMean = meanLuminance(reference);
    if (a.json) {
        nlohmann::json j = metricsJson(m);
        j["image"] = a.image;
        j["reference"] = a.reference;
        j["width"] = image.width;
        j["height"] = image.height;
        j["meanLuminance"] = mean;
        j["referenceMeanLuminance"] = referenceMean;
        for (const Metric k : allMetrics()) j["definitions"][metricName(k)] = metricDefinition(k, m.options.epsilon);
        if (renderSeconds > 0) {
            j["renderSeconds"] = renderSeconds;
            j["efficiency"] = efficiency(m.relMse, renderSeconds);
            j["definitions"]["efficiency"] = "1 / (relmse x renderSeconds)";
        }
        std::printf("%s\n", j.dump(2).c_str());
        return 0;
    }
    std::printf("%s against the reference %s: %dx%d, epsilon %g, trim: %s\n", a.image.c_str(), a.reference.c_str(),
                image.width, image.height, m.options.epsilon,
                m.trimmedPixels > 0 ? (std::to_string(m.trimmedPixels) + " of " + std::to_string(m.pixels) +
                                       " pixels (highest errors) discarded per metric")
                                          .c_str()
                                    : "none");
    for (const Metric k : allMetrics())
        std::printf("  %-10s %-14.6g %s\n", metricName(k).c_str(), m.get(k),
                    metricDefinition(k, m.options.epsilon).c_str());
    std::printf("  %-10s %-14.6g mean luminance %.6g against the reference's %.6g\n", "mean ratio",
                referenceMean > 0 ? mean / referenceMean : 0.0, mean, referenceMean);
    if (renderSeconds > 0)
        std::printf("  %-10s %-14.6g 1 / (relmse x %g s of rendering)\n", "efficiency",
                    efficiency(m.relMse, renderSeconds), renderSeconds);
    return 0;
}

}  // namespace pf::client
