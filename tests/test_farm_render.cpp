// The farm renders what the embedded renderer renders, bit for bit, with real master and worker
// processes on loopback, also while workers are killed (SIGKILL) in the middle of their tasks or fail
// every task they are given.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>

#include "farm/harness.h"
#include "image/bitmap.h"
#include "render/image_task.h"
#include "scene/scene.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

class FarmRender : public FarmTest {
protected:
    // The embedded render of the same spec, the reference every farm image must equal.
    std::string reference(const std::string &scene, const std::string &args) {
        return farm->embeddedRender(scene, args, "reference");
    }
    // A timed job's image: the embedded render of its whole tasks' sample count, bit for bit, except where it
    // ended with a partial task (one sample in the film's first tiles; render/image_task.h), whose covered
    // pixels have the next count's bits. Returns the pixels with the partial task's sample.
    int expectTimedImage(const std::string &scene, const std::string &args, const std::string &out) {
        const Bitmap img = readEXR(out);
        const int spp = std::stoi(img.metadata.at("pathfarm.spp"));
        const std::string whole = farm->embeddedRender(scene, "--spp " + std::to_string(spp) + " " + args, "whole");
        const auto partial = img.metadata.find("pathfarm.partialPassPixels");
        if (partial == img.metadata.end()) {
            EXPECT_TRUE(sameBits(whole, out));
            return 0;
        }
        const auto loaded = loadScene(scene);
        const Film &film = loaded->sensor().film();
        const int64_t pixels = std::stoll(partial->second);
        int64_t tiles = 0;
        while (tilePixels(film, tiles) < pixels) ++tiles;
        EXPECT_EQ(tilePixels(film, tiles), pixels) << "whole tiles";
        const std::vector<char> footprint = partialPassFootprints(film, tiles);
        const Bitmap a = readEXR(whole);
        const Bitmap b = readEXR(farm->embeddedRender(scene, "--spp " + std::to_string(spp + 1) + " " + args, "next"));
        int gained = 0;
        for (size_t i = 0; i < footprint.size(); ++i) {
            const Bitmap &expected = footprint[i] ? b : a;
            for (size_t c = 0; c < 3; ++c)
                if (img.rgb[3 * i + c] != expected.rgb[3 * i + c]) {
                    ADD_FAILURE() << "pixel " << i << (footprint[i] ? " (covered)" : "") << ": " << img.rgb[3 * i + c]
                                  << " against " << expected.rgb[3 * i + c];
                    return gained;
                }
            gained += footprint[i];
        }
        std::printf("the partial task covered %lld tiles; %d pixels took its sample\n", static_cast<long long>(tiles),
                    gained);
        return gained;
    }
};

TEST_F(FarmRender, ThreeWorkersMatchTheEmbeddedRenderBitForBit) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 48, 8);
    const std::string spec = "--spp 40 --seed 7 -P maxDepth=4";
    const std::string ref = reference(scene, spec);
    farm->startMaster(kFastLeases);
    for (int i = 0; i < 3; ++i) farm->startWorker(1);
    const std::string out = farm->dir() + "/farm.exr";
    const auto [code, output] = farm->cli("submit " + scene + " " + spec + " --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    EXPECT_TRUE(sameBits(ref, out));
    const Bitmap img = readEXR(out);
    EXPECT_EQ(img.metadata.at("pathfarm.spp"), "40");
    EXPECT_EQ(img.metadata.at("pathfarm.seed"), "7");
    EXPECT_EQ(img.metadata.at("pathfarm.integrator"), "path");
    EXPECT_TRUE(img.metadata.count("pathfarm.renderSeconds"));

    // The job record and the workers agree with what happened: 5 tasks of 8 spp, each merged once.
    const int64_t id = jobIdFrom(output);
    const v1::Job job = farm->waitForJob(id, 10s);
    EXPECT_EQ(job.tasks().total(), 5);
    EXPECT_EQ(job.tasks().merged(), 5);
    EXPECT_EQ(job.samples_per_pixel(), 40);
    EXPECT_GT(job.render_seconds(), 0);
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + std::to_string(id)), 5);
    const auto [wcode, workers] = farm->cli("workers");
    EXPECT_EQ(wcode, 0) << workers;
    EXPECT_EQ(std::count(workers.begin(), workers.end(), '\n'), 4) << workers;  // header + 3 workers
    const auto [scode, status] = farm->cli("status");
    EXPECT_NE(status.find("done"), std::string::npos) << status;
    const auto [fcode, fetched] = farm->cli("fetch " + std::to_string(id) + " -o " + farm->dir() + "/again.exr");
    EXPECT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, farm->dir() + "/again.exr"));
}

// A scene whose <sampler> is low-discrepancy: tasks cover ranges of each pixel's samples, and a sample's numbers
// depend on its index within the pixel only (core/ld_sampler.h), so two workers splitting the samples into
// tasks render the embedded image bit for bit, for the path tracer and for BDPT's light-tracing splats.
TEST_F(FarmRender, LowDiscrepancySamplesMatchTheEmbeddedRenderBitForBit) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 32, 8);
    std::string xml = pf::farm::readFile(scene);
    const size_t at = xml.find("<sampler type=\"independent\">");
    ASSERT_NE(at, std::string::npos);
    xml.replace(at, std::string("<sampler type=\"independent\">").size(),
                "<sampler type=\"ldsampler\"><integer name=\"dimension\" value=\"3\"/>");
    writeFile(farm->dir() + "/scene", "scene.xml", xml);
    farm->startMaster();
    farm->startWorker(1);
    farm->startWorker(2);
    for (const std::string integrator : {"path", "bdpt"}) {
        std::string farmImage, embeddedImage;
        farm->submitMatchingEmbedded(scene, "--integrator " + integrator + " --spp 40 --seed 3", farmImage,
                                     embeddedImage);
    }
}

TEST_F(FarmRender, KilledWorkersDoNotChangeTheImage) {
    // Tasks of a few hundred milliseconds, so that a worker that has started one is killed inside it.
    const std::string scene = writeTestScene(farm->dir() + "/scene", 128, 8);
    const std::string spec = "--spp 64 --seed 3";
    const std::string ref = reference(scene, spec);
    farm->startMaster(kFastLeases);
    const auto [code, output] = farm->cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    // Each victim is alone with the job, so it cannot end before all three have died in a task.
    for (int kill = 0; kill < 3; ++kill) {
        Process &victim = farm->startWorker(1);
        ASSERT_TRUE(waitUntil([&] { return victim.log().find("rendering samples") != std::string::npos; }, 60s))
            << victim.log();
        victim.signal(SIGKILL);
        victim.wait(10s);
    }
    farm->startWorker(1);
    farm->startWorker(1);
    const v1::Job job = farm->waitForJob(id, 240s);
    ASSERT_EQ(job.state(), v1::JOB_DONE) << job.DebugString();
    EXPECT_GE(job.tasks().expired_attempts(), 3);
    const auto [fcode, fetched] = farm->cli("fetch " + std::to_string(id) + " -o " + farm->dir() + "/farm.exr");
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, farm->dir() + "/farm.exr"));
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + std::to_string(id)), 8);
}

TEST_F(FarmRender, AWorkerThatFailsEveryTaskIsBlocklisted) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 32, 8);
    const std::string spec = "--spp 48 --seed 11";
    const std::string ref = reference(scene, spec);
    farm->startMaster({"--max-failures-per-worker", "3"});
    Process &bad = farm->startWorker(1, {"--fail-every-task"});
    const auto [code, output] = farm->cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    // Alone, the faulty worker fails tasks until it is blocklisted; then a good worker finishes the job.
    ASSERT_TRUE(waitUntil(
        [&] { return farm->queryStore("SELECT COUNT(*) FROM blocklist WHERE job_id = " + std::to_string(id)) == 1; },
        60s))
        << bad.log() << farm->master().log();
    farm->startWorker(1);
    const v1::Job job = farm->waitForJob(id, 120s);
    ASSERT_EQ(job.state(), v1::JOB_DONE) << job.DebugString();
    ASSERT_EQ(job.blocklisted_workers_size(), 1);
    EXPECT_EQ(job.tasks().failed_attempts(), 3);
    const auto [fcode, fetched] = farm->cli("fetch " + std::to_string(id) + " -o " + farm->dir() + "/farm.exr");
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, farm->dir() + "/farm.exr"));
    EXPECT_TRUE(bad.running());  // blocklisted for this job only; it keeps asking for work
}

TEST_F(FarmRender, TimeBudgetIssuesWholeTasksThenAPartialOneAndRecordsTheTrueTime) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 32, 8);
    farm->startMaster();
    farm->startWorker(1);
    const std::string out = farm->dir() + "/timed.exr";
    const auto [code, output] = farm->cli("submit " + scene + " --time 1.5 --seed 5 --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    const Bitmap img = readEXR(out);
    const int spp = std::stoi(img.metadata.at("pathfarm.spp"));
    EXPECT_GE(spp, 8);
    EXPECT_EQ(spp % 8, 0);  // whole tasks, and at most a partial one after them
    const double seconds = std::stod(img.metadata.at("pathfarm.renderSeconds"));
    EXPECT_GT(seconds, 0.5);
    EXPECT_LT(seconds, 30);
    const v1::Job job = farm->waitForJob(jobIdFrom(output), 10s);
    EXPECT_NEAR(job.render_seconds(), seconds, 1.0);
    // A timed job of n tasks has the bits of an spp job of the same sample count, and a partial last task's
    // pixels those of the next count.
    expectTimedImage(scene, "--seed 5", out);
    // `submit --wait` says what `render` says of a partial last pass.
    if (const auto partial = img.metadata.find("pathfarm.partialPassPixels"); partial != img.metadata.end()) {
        char line[64];
        std::snprintf(line, sizeof line, "final image, %d spp + 1 in %.0f%% of pixels", spp,
                      100.0 * std::stod(partial->second) / (32 * 32));
        EXPECT_NE(output.find(line), std::string::npos) << output;
    } else {
        EXPECT_EQ(output.find(" + 1 in "), std::string::npos) << output;
    }
}

// A timed job ends when its last result is merged, so the budget must hold each task's transfer and merge as
// well as its rendering. Here every upload is held back by a second, as on a slow link: counted by its
// rendering alone, the last task was issued as the budget ran out and arrived a second or two after it.
TEST_F(FarmRender, TimeBudgetHoldsTheTransferOfTheLastTask) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 32, 8);
    farm->startMaster();
    farm->startWorker(1, {"--upload-delay", "1"});
    const std::string out = farm->dir() + "/timed.exr";
    const double budget = 5;
    const auto [code, output] = farm->cli("submit " + scene + " --time 5 --seed 5 --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    const Bitmap img = readEXR(out);
    const double seconds = std::stod(img.metadata.at("pathfarm.renderSeconds"));
    EXPECT_LT(seconds, budget + 0.4) << farm->master().log();
    EXPECT_GT(seconds, budget - 2.5) << farm->master().log();  // and it still used the budget
    expectTimedImage(scene, "--seed 5", out);
}

// A large film under a time budget: before any result tells the job's pace, the workers get only the
// sequence's smallest tasks (1 spp at 1024²), however many of them ask; afterwards a task is issued only if
// it is expected to end within the budget. (A 1024² BDPT job under --time 20 ran 52 s when its first task
// was 8 spp and the estimate counted tasks rather than samples.)
TEST_F(FarmRender, TimeBudgetOnALargeFilmStartsWithItsSmallestTasks) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 1024, 8);
    farm->startMaster();
    for (int i = 0; i < 3; ++i) farm->startWorker(1);
    const std::string out = farm->dir() + "/timed.exr";
    const double budget = 4;
    const auto [code, output] = farm->cli("submit " + scene + " --time 4 --seed 3 -P maxDepth=2 --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    const std::string log = farm->master().log();
    const size_t firstResult = log.find("accepted,");
    ASSERT_NE(firstResult, std::string::npos) << log;
    int blind = 0;
    for (size_t at = log.find("leased, samples ["); at < firstResult; at = log.find("leased, samples [", at + 1)) {
        long long from = 0, to = 0;
        ASSERT_EQ(std::sscanf(log.c_str() + at, "leased, samples [%lld, %lld)", &from, &to), 2);
        EXPECT_EQ(to - from, 1) << "a task issued before any result: " << log.substr(at, 40);
        ++blind;
    }
    EXPECT_GE(blind, 1) << log;
    const Bitmap img = readEXR(out);
    const int spp = std::stoi(img.metadata.at("pathfarm.spp"));
    EXPECT_GE(spp, 1);
    // Whole tasks that each fit the budget when issued: the job ends within a task's time of the budget.
    const double seconds = std::stod(img.metadata.at("pathfarm.renderSeconds"));
    EXPECT_LT(seconds, 3 * budget) << log;
    expectTimedImage(scene, "--seed 3 -P maxDepth=2", out);
}

TEST_F(FarmRender, CancelStopsAJobAndKeepsItsImage) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 64, 8);
    farm->startMaster(kFastLeases);
    farm->startWorker(1);
    const auto [code, output] = farm->cli("submit " + scene + " --spp 100000");
    ASSERT_EQ(code, 0) << output;
    const std::string id = std::to_string(jobIdFrom(output));
    ASSERT_TRUE(
        waitUntil([&] { return farm->queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + id) > 0; }, 60s));
    const auto [ccode, cancelled] = farm->cli("cancel " + id);
    EXPECT_EQ(ccode, 0) << cancelled;
    EXPECT_NE(cancelled.find("cancelled"), std::string::npos) << cancelled;
    const auto [wcode, watched] = farm->cli("watch " + id);
    EXPECT_EQ(wcode, 1) << watched;  // the job did not complete
    const auto [fcode, fetched] = farm->cli("fetch " + id + " -o " + farm->dir() + "/partial.exr");
    EXPECT_EQ(fcode, 0) << fetched;
    EXPECT_NE(fetched.find("running image"), std::string::npos) << fetched;
    EXPECT_EQ(readEXR(farm->dir() + "/partial.exr").width, 64);
}

TEST_F(FarmRender, SigtermDrainsAWorkerAfterItsTask) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 128, 8);
    farm->startMaster(kFastLeases);
    Process &worker = farm->startWorker(1);
    const auto [code, output] = farm->cli("submit " + scene + " --spp 64 --seed 1");
    ASSERT_EQ(code, 0) << output;
    ASSERT_TRUE(waitUntil([&] { return worker.log().find("rendering samples") != std::string::npos; }, 60s));
    worker.signal(SIGTERM);
    const auto exitCode = worker.wait(60s);
    ASSERT_TRUE(exitCode) << worker.log();
    EXPECT_EQ(*exitCode, 0) << worker.log();
    // The task in hand (and one leased just before the signal) was finished and delivered, not
    // abandoned to an expiring lease.
    EXPECT_GE(farm->queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'completed'"), 1) << worker.log();
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM attempts WHERE state <> 'completed'"), 0) << worker.log();
}

TEST_F(FarmRender, HigherPriorityJobsAreLeasedFirst) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 24, 8);
    farm->startMaster();
    const auto [lowCode, low] = farm->cli("submit " + scene + " --spp 32 --priority 0");
    const auto [highCode, high] = farm->cli("submit " + scene + " --spp 32 --priority 5");
    ASSERT_EQ(lowCode + highCode, 0) << low << high;
    farm->startWorker(1);
    const std::string lowId = std::to_string(jobIdFrom(low)), highId = std::to_string(jobIdFrom(high));
    EXPECT_EQ(farm->waitForJob(jobIdFrom(low), 60s).state(), v1::JOB_DONE);
    // Every task of the urgent job was leased before the first task of the other.
    EXPECT_LT(farm->queryStore("SELECT MAX(id) FROM attempts WHERE job_id = " + highId),
              farm->queryStore("SELECT MIN(id) FROM attempts WHERE job_id = " + lowId));
}

}  // namespace
}  // namespace pf::test::farm
