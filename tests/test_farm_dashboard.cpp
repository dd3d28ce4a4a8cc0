// The dashboard in a real browser: Debian's Chromium, headless, loads the master's page while a job
// renders, runs its script against the live JSON API, and leaves a screenshot and the DOM as the script
// built it. The DOM must show the running job with its progress bar, the worker and a loaded preview;
// the screenshot's preview frame must hold the job's image (not an empty frame): its pixels vary and
// their mean colour is that of the preview PNG the master serves.
#include <gtest/gtest.h>
#include <httplib.h>

#include <cmath>
#include <regex>

#include "../master/dashboard.h"
#include "farm/harness.h"
#include "image/bitmap.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

constexpr int kWindowWidth = 1280, kWindowHeight = 800;

// Debian's package installs `chromium`; other distributions call it chromium-browser.
std::string chromiumBinary() {
    for (const char *name : {"chromium", "chromium-browser"}) {
        const ProcessResult r = runCommand(std::string("command -v ") + name);
        if (r.exitCode == 0) return r.output.substr(0, r.output.find('\n'));
    }
    return "";
}

struct Rgb {
    double r = 0, g = 0, b = 0;
};
struct RegionStats {
    Rgb mean;
    double lumaStddev = 0;
};
RegionStats regionStats(const Bitmap &img, int x0, int y0, int x1, int y1) {
    RegionStats s;
    double sum = 0, sum2 = 0;
    const double n = static_cast<double>(x1 - x0) * (y1 - y0);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            const float *p = &img.rgb[3 * (static_cast<size_t>(y) * img.width + x)];
            s.mean.r += p[0] / n;
            s.mean.g += p[1] / n;
            s.mean.b += p[2] / n;
            const double luma = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
            sum += luma;
            sum2 += luma * luma;
        }
    s.lumaStddev = std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
    return s;
}

TEST(FarmDashboard, ChromiumShowsTheRunningJobItsWorkerAndALivePreview) {
    const std::string chromium = chromiumBinary();
    ASSERT_FALSE(chromium.empty()) << "Chromium is not installed (scripts/install-deps.sh installs Debian's chromium)";

    Farm farm("dashboard");
    const int port = freePort();
    farm.startMaster({"--http", "127.0.0.1:" + std::to_string(port)});
    farm.startWorker(1);
    // A time budget keeps the job running for as long as the browser needs; it is cancelled at the end.
    const std::string scene = writeTestScene(farm.dir() + "/scene", 64, 8);
    const auto [code, output] = farm.cli("submit " + scene + " --time 120 --label dashboard-test");
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    const auto stub = farm.clientStub();
    ASSERT_TRUE(waitUntil(
        [&] {
            v1::GetJobRequest req;
            req.set_id(id);
            v1::Job job;
            return stub->GetJob(farm.context(farm.clientToken(), 5).get(), req, &job).ok() && job.tasks().merged() >= 2;
        },
        30s))
        << farm.master().log();

    // One browser run leaves both the screenshot and the DOM; the virtual time budget lets the page's
    // script poll the API a few times and load the preview first.
    const std::string shot = farm.dir() + "/dashboard.png", dom = farm.dir() + "/dashboard.html";
    const ProcessResult browser = runCommand(
        "(timeout 120 " + chromium +
        " --headless --no-sandbox --disable-gpu --no-first-run --no-default-browser-check --user-data-dir=" +
        farm.dir() + "/chromium-profile --window-size=" + std::to_string(kWindowWidth) + "," +
        std::to_string(kWindowHeight) + " --virtual-time-budget=4000 --screenshot=" + shot +
        " --dump-dom http://127.0.0.1:" + std::to_string(port) + "/ > " + dom + " 2> " + farm.dir() + "/chromium.log)");
    ASSERT_EQ(browser.exitCode, 0) << pf::farm::readFile(farm.dir() + "/chromium.log");
    const std::string page = pf::farm::readFile(dom);
    const std::string job = std::to_string(id);

    // The jobs table: the job's row, running, with a progress bar that has moved, and its label.
    std::smatch m;
    ASSERT_TRUE(std::regex_search(page, m, std::regex("<tr class=\"job[^\"]*\" data-job=\"" + job + "\">(.*?)</tr>")))
        << page;
    const std::string jobRow = m[1];
    EXPECT_NE(jobRow.find("<span class=\"state running\">running</span>"), std::string::npos) << jobRow;
    EXPECT_NE(jobRow.find("dashboard-test"), std::string::npos) << jobRow;
    EXPECT_NE(jobRow.find(">path<"), std::string::npos) << jobRow;
    ASSERT_TRUE(std::regex_search(jobRow, m, std::regex("class=\"bar\"><div style=\"width: ([0-9.]+)%;\">"))) << jobRow;
    EXPECT_GT(std::stod(m[1]), 0.0) << jobRow;
    // The workers table and the summary.
    EXPECT_TRUE(std::regex_search(page, std::regex("<td>worker-0</td><td>127\\.0\\.0\\.1:\\d+</td>"))) << page;
    EXPECT_NE(page.find("running <b>1</b>"), std::string::npos) << page;
    // The preview: the script swaps an image in only once it has loaded.
    EXPECT_NE(page.find("<aside id=\"preview\" class=\"loaded\">"), std::string::npos) << page;
    EXPECT_TRUE(std::regex_search(page, std::regex("<img alt=\"live preview\" src=\"http://127\\.0\\.0\\.1:" +
                                                   std::to_string(port) + "/api/v1/jobs/" + job + "/preview\\.png")))
        << page;
    EXPECT_TRUE(std::regex_search(page, std::regex("<figcaption>Job " + job + " · running · 64×64 · \\d+ spp")))
        << page;

    // The screenshot: inside the preview frame (pinned by the page's CSS, master/dashboard.h), the job's
    // image. An empty frame is one flat colour; the image varies, and its mean colour is the preview's.
    const Bitmap screen = readLDR(shot, false);
    ASSERT_EQ(screen.width, kWindowWidth);
    ASSERT_EQ(screen.height, kWindowHeight);
    const int inset = 8;
    const int x1 = kWindowWidth - master::kPreviewFrameRightPx, x0 = x1 - master::kPreviewFramePx;
    const int y0 = master::kPreviewFrameTopPx, y1 = y0 + master::kPreviewFramePx;
    const RegionStats shown = regionStats(screen, x0 + inset, y0 + inset, x1 - inset, y1 - inset);
    EXPECT_GT(shown.lumaStddev, 0.05) << "the preview region of the screenshot is flat";

    httplib::Client http("127.0.0.1", port);
    const auto res = http.Get("/api/v1/jobs/" + job + "/preview.png");
    ASSERT_TRUE(res && res->status == 200);
    const Bitmap preview = readLDR(writeFile(farm.dir(), "preview.png", res->body), false);
    const RegionStats served = regionStats(preview, 0, 0, preview.width, preview.height);
    EXPECT_NEAR(shown.mean.r, served.mean.r, 0.04);
    EXPECT_NEAR(shown.mean.g, served.mean.g, 0.04);
    EXPECT_NEAR(shown.mean.b, served.mean.b, 0.04);

    const auto [cancelCode, cancelled] = farm.cli("cancel " + job);
    EXPECT_EQ(cancelCode, 0) << cancelled;
}

}  // namespace
}  // namespace pf::test::farm
