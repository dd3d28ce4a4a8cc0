// `pathfarm compare` as a user runs it: real CLI, master and worker processes (the embedded farm the CLI
// starts itself, or a farm of the test's own for --master), real files read back, the report page opened
// in headless Chromium.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "farm/harness.h"
#include "image/bitmap.h"
#include "image/metrics.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json readJson(const std::string &path) {
    std::ifstream in(path);
    return json::parse(in);
}

class Compare : public ::testing::Test {
protected:
    void SetUp() override {
        cli = cliPath();
        ASSERT_FALSE(cli.empty()) << "PATHFARM_CLI is not set (run through ctest)";
        dir = tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
        // 32x32 pixels: a run's tasks take milliseconds, so a second holds many of them.
        scene = farm::writeTestScene(dir + "/scene", 32, 4);
        // The embedded farms of this test keep their files here (and nowhere that other tests look).
        tmp = dir + "/tmp";
        fs::create_directories(tmp);
    }
    ProcessResult compare(const std::string &args) {
        return runCommand("TMPDIR=" + tmp + " " + cli + " compare " + scene + " --cache-dir " + dir +
                          "/cache --threads 2 " + args);
    }
    std::string cli, dir, scene, tmp;
};

TEST_F(Compare, TwoIntegratorsGiveReportConsistentWithDiff) {
    const std::string out = dir + "/report";
    const ProcessResult r =
        compare("--integrators path,bdpt --time 1 --repeat 2 --snapshots 4 --reference-spp 64 --seed 5 -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char *f : {"index.html", "report.json", "reference.exr", "reference.png", "path-0.exr", "path-0.png",
                          "path-1.exr", "bdpt-0.exr", "bdpt-1.exr", "bdpt-1.png", "path-0-error.png",
                          "bdpt-1-error.png", "crop1-reference.png", "crop1-path.png", "crop1-bdpt.png"})
        EXPECT_TRUE(fs::is_regular_file(out + "/" + f)) << f;

    const json j = readJson(out + "/report.json");
    EXPECT_EQ(j["farm"]["embedded"], true);
    EXPECT_EQ(j["farm"]["workers"].size(), 1u);
    EXPECT_EQ(j["reference"]["source"], "rendered");
    EXPECT_EQ(j["reference"]["spp"], 64);
    EXPECT_EQ(j["metrics"]["epsilon"], 0.01);
    EXPECT_EQ(j["metrics"]["trimFraction"], 0.0);
    EXPECT_EQ(j["width"], 32);
    ASSERT_EQ(j["runs"].size(), 4u);
    std::map<std::string, std::vector<double>> relMse;
    for (const json &run : j["runs"]) {
        const std::string exr = out + "/" + run["exr"].get<std::string>();
        SCOPED_TRACE(exr);
        EXPECT_EQ(run["seed"], 5 + run["repetition"].get<int>());
        // Equal time: whole tasks are issued while the budget lasts, so the true time is about the budget.
        EXPECT_GT(run["renderSeconds"].get<double>(), 0.8);
        EXPECT_LT(run["renderSeconds"].get<double>(), 3.0);
        EXPECT_GE(run["sceneLoadSeconds"].get<double>(), 0.0);
        EXPECT_GT(run["spp"].get<int64_t>(), 8);
        // The report's numbers are those `pathfarm diff` prints for the same files.
        const ProcessResult d = runCommand(cli + " diff " + exr + " " + out + "/reference.exr --json");
        ASSERT_EQ(d.exitCode, 0) << d.output;
        const json dj = json::parse(d.output);
        for (const Metric m : allMetrics())
            EXPECT_DOUBLE_EQ(run["metrics"][metricName(m)].get<double>(), dj[metricName(m)].get<double>())
                << metricName(m);
        const double rel = run["metrics"]["relmse"].get<double>();
        EXPECT_DOUBLE_EQ(run["efficiency"].get<double>(), 1 / (rel * run["renderSeconds"].get<double>()));
        relMse[run["integrator"]].push_back(rel);
        // Snapshots: the running image at increasing times with increasing sample counts, all before the end.
        ASSERT_GE(run["snapshots"].size(), 1u);
        double t = 0;
        int64_t spp = 0;
        for (const json &s : run["snapshots"]) {
            EXPECT_GT(s["seconds"].get<double>(), t);
            EXPECT_GE(s["spp"].get<int64_t>(), spp);
            t = s["seconds"];
            spp = s["spp"];
            EXPECT_GT(s["metrics"]["relmse"].get<double>(), 0.0);
        }
        EXPECT_LT(spp, run["spp"].get<int64_t>());
    }
    // Unbiased methods against an unbiased reference: errors are noise, small after a second of 32x32.
    for (const auto &[name, values] : relMse)
        for (double v : values) EXPECT_LT(v, 0.5) << name;
    // Summary: mean and sample standard deviation over the two repetitions.
    ASSERT_EQ(j["summary"].size(), 2u);
    for (const json &s : j["summary"]) {
        const std::vector<double> &v = relMse[s["integrator"]];
        ASSERT_EQ(v.size(), 2u);
        EXPECT_DOUBLE_EQ(s["relmse"]["mean"].get<double>(), (v[0] + v[1]) / 2);
        EXPECT_NEAR(s["relmse"]["stddev"].get<double>(), std::abs(v[0] - v[1]) / std::sqrt(2.0), 1e-12);
    }

    // A second comparison of the same scene takes the reference from the cache.
    const ProcessResult again =
        compare("--integrators path --time 0.3 --snapshots 0 --reference-spp 64 --seed 5 -o " + dir + "/again");
    ASSERT_EQ(again.exitCode, 0) << again.output;
    const json j2 = readJson(dir + "/again/report.json");
    EXPECT_EQ(j2["reference"]["source"], "cache");
    EXPECT_EQ(j2["reference"]["cacheFile"], j["reference"]["cacheFile"]);
    EXPECT_TRUE(farm::sameBits(out + "/reference.exr", dir + "/again/reference.exr"));
}

TEST_F(Compare, PageShowsImagesTableAndPlotInChromium) {
    const ProcessResult which = runCommand("command -v chromium");
    ASSERT_EQ(which.exitCode, 0) << "chromium is missing: scripts/install-deps.sh installs it";
    const std::string out = dir + "/report";
    const ProcessResult r = compare("--integrators path,bdpt --time 0.3 --snapshots 3 --reference-spp 16 -o " + out);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // One browser run (a start costs seconds): the DOM on stdout, the screenshot to a file.
    const std::string shotFile = dir + "/shot.png";
    const ProcessResult dom =
        runCommand("chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir=" + dir +
                   "/chromium --window-size=1400,2600 --screenshot=" + shotFile + " --dump-dom file://" +
                   fs::absolute(out + "/index.html").string() + " 2>/dev/null");
    ASSERT_EQ(dom.exitCode, 0) << dom.output;
    for (const char *s : {"<img src=\"reference.png\"", "<img src=\"path-0.png\"", "<img src=\"bdpt-0.png\"",
                          "<img src=\"bdpt-0-error.png\"", "id=\"metrics-table\"", "<td>path</td>", "<td>bdpt</td>",
                          "<svg class=\"plot\"", "<polyline", "data-label=\"bdpt\"", "(b^2 + 0.01)"})
        EXPECT_NE(dom.output.find(s), std::string::npos) << s;

    const Bitmap shot = readLDR(shotFile, false);
    ASSERT_EQ(shot.width, 1400);
    double mean = 0, var = 0;
    for (float v : shot.rgb) mean += v;
    mean /= static_cast<double>(shot.rgb.size());
    for (float v : shot.rgb) var += (v - mean) * (v - mean);
    var /= static_cast<double>(shot.rgb.size());
    EXPECT_GT(var, 1e-3) << "blank screenshot";
    // The error maps are drawn: their saturated colour (pale yellow, sRGB 252, 254, 164: the top 1% of
    // per-pixel errors, each shown 8x8 times enlarged) appears nowhere else on the page.
    int saturated = 0;
    for (size_t p = 0; p < shot.rgb.size() / 3; ++p)
        saturated += std::abs(shot.rgb[3 * p] * 255 - 252) < 4 && std::abs(shot.rgb[3 * p + 1] * 255 - 254) < 4 &&
                     std::abs(shot.rgb[3 * p + 2] * 255 - 164) < 4;
    EXPECT_GT(saturated, 64) << "the error maps are not drawn";
}

TEST_F(Compare, MasterModeRunsOnTheGivenFarm) {
    farm::Farm f("CompareMasterMode");
    f.startMaster();
    f.startWorker(2);
    // A reference file given: nothing is rendered for it.
    ASSERT_EQ(runCommand(cli + " render " + scene + " -q --integrator bdpt --spp 32 -o " + dir + "/ref.exr").exitCode,
              0);
    const ProcessResult r = runCommand(cli + " compare " + scene + " --integrators path --time 0.5 --snapshots 2" +
                                       " --reference " + dir + "/ref.exr --master " + f.address() + " --token-file " +
                                       f.clientTokenFile() + " -o " + dir + "/report");
    ASSERT_EQ(r.exitCode, 0) << r.output << f.master().log();
    const json j = readJson(dir + "/report/report.json");
    EXPECT_EQ(j["farm"]["embedded"], false);
    EXPECT_EQ(j["farm"]["master"], f.address());
    EXPECT_EQ(j["reference"]["source"], "file");
    ASSERT_EQ(j["runs"].size(), 1u);
    const int64_t job = j["runs"][0]["job"];
    EXPECT_EQ(f.queryStore("SELECT COUNT(*) FROM jobs"), 1);  // the run, and no reference job
    EXPECT_EQ(f.queryStore("SELECT COUNT(*) FROM jobs WHERE id = " + std::to_string(job)), 1);
    EXPECT_TRUE(farm::sameBits(dir + "/ref.exr", dir + "/report/reference.exr"));
}

TEST_F(Compare, BadOptionsAreClearErrorsWithExitTwo) {
    writeFile(dir, "text.exr", "not an image\n");
    ASSERT_EQ(runCommand(cli + " render " + scene + " -q --spp 2 -D res=16 -o " + dir + "/small.exr").exitCode, 0);
    ASSERT_EQ(runCommand(cli + " render " + scene + " -q --spp 2 -o " + dir + "/full.exr").exitCode, 0);
    struct Case {
        std::string args, expected;
    };
    const std::string o = " -o " + dir + "/out";
    const std::vector<Case> cases = {
        {"--integrators path,nosuch --time 1" + o, "unknown integrator 'nosuch'"},
        {"--integrators path" + o, "--time"},
        {"--integrators path --time 0" + o, "--time"},
        {"--integrators path --time 1 --reference " + dir + "/missing.exr" + o, dir + "/missing.exr"},
        {"--integrators path --time 1 --reference " + dir + "/text.exr" + o, dir + "/text.exr"},
        {"--integrators path --time 1 --reference " + dir + "/small.exr --reference-spp 4" + o, "--reference"},
        {"--integrators path --time 1 -P maxDepth" + o, "-P"},
        // An unused parameter is a warning, unless --strict makes the farm refuse the runs.
        {"--integrators path --time 1 --strict -P noSuchParameter=1 --reference " + dir + "/full.exr" + o,
         "unknown parameter 'noSuchParameter'"},
        // Found once the farm has accepted the job and reported its size.
        {"--integrators path --time 1 --reference " + dir + "/small.exr" + o,
         dir + "/small.exr: the reference is 16x16 but the scene renders 32x32"},
    };
    for (const Case &c : cases) {
        const ProcessResult r = compare(c.args);
        EXPECT_EQ(r.exitCode, 2) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    }
    // No process of the embedded farms outlived the comparisons, and their directories are gone.
    EXPECT_NE(runCommand("pgrep -f '" + tmp + "/pathfarm-compar[e]-' >/dev/null").exitCode, 0);
    EXPECT_TRUE(fs::is_empty(tmp));
}

}  // namespace
}  // namespace pf::test
