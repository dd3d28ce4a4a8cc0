// The master's HTTP status with real processes: JSON derived from the proto messages, Prometheus
// metrics, liveness and readiness, the dashboard page and a preview PNG of the job's image.
#include <gtest/gtest.h>
#include <httplib.h>

#include <filesystem>

#include "farm/harness.h"
#include "image/bitmap.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

using namespace std::chrono_literals;

TEST(FarmHttp, StatusPagesShowJobsWorkersAndAPreview) {
    Farm farm("http");
    const int port = freePort();
    farm.startMaster({"--http", "127.0.0.1:" + std::to_string(port)});
    farm.startWorker(1);
    const std::string scene = writeTestScene(farm.dir() + "/scene", 32, 8);
    const auto [code, output] =
        farm.cli("submit " + scene + " --spp 16 --label http-test --wait -o " + farm.dir() + "/out.exr");
    ASSERT_EQ(code, 0) << output;
    const std::string id = std::to_string(jobIdFrom(output));

    httplib::Client http("127.0.0.1", port);
    http.set_read_timeout(10, 0);
    auto get = [&](const std::string &path) {
        const auto res = http.Get(path.c_str());
        EXPECT_TRUE(res) << path;
        return res ? std::make_pair(res->status, res->body) : std::make_pair(0, std::string());
    };
    EXPECT_EQ(get("/livez").first, 200);
    EXPECT_EQ(get("/readyz").first, 200);

    const auto [jobsStatus, jobs] = get("/api/v1/jobs");
    EXPECT_EQ(jobsStatus, 200);
    EXPECT_NE(jobs.find("\"label\":\"http-test\""), std::string::npos) << jobs;
    const auto [jobStatus, job] = get("/api/v1/jobs/" + id);
    EXPECT_EQ(jobStatus, 200);
    EXPECT_NE(job.find("\"state\":\"JOB_DONE\""), std::string::npos) << job;
    EXPECT_NE(job.find("\"samples_per_pixel\":\"16\""), std::string::npos) << job;
    EXPECT_EQ(get("/api/v1/jobs/999").first, 404);
    const auto [workersStatus, workers] = get("/api/v1/workers");
    EXPECT_NE(workers.find("\"name\":\"worker-0\""), std::string::npos) << workers;

    const auto [metricsStatus, metrics] = get("/metrics");
    EXPECT_EQ(metricsStatus, 200);
    EXPECT_NE(metrics.find("pathfarm_tasks{state=\"merged\"} 2"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("pathfarm_workers{state=\"alive\"} 1"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("pathfarm_merge_seconds_total"), std::string::npos) << metrics;

    const auto [pageStatus, page] = get("/");
    EXPECT_EQ(pageStatus, 200);
    EXPECT_NE(page.find("pathfarm master"), std::string::npos);

    // The preview is a real PNG of the job's image, not a blank one.
    const auto [pngStatus, png] = get("/api/v1/jobs/" + id + "/preview.png");
    ASSERT_EQ(pngStatus, 200);
    const std::string pngPath = writeFile(farm.dir(), "preview.png", png);
    const Bitmap preview = readLDR(pngPath, false);
    EXPECT_EQ(preview.width, 32);
    float brightest = 0;
    for (const float v : preview.rgb) brightest = std::max(brightest, v);
    EXPECT_GT(brightest, 0.1f);
}

}  // namespace
}  // namespace pf::test::farm
