// The master's failure rules with real processes: a master killed (SIGKILL) in the middle of a job
// resumes it from its store with nothing lost and nothing merged twice, a result that arrives after
// its task was given to another attempt is ignored, and a draining worker whose master is gone exits.
#include <gtest/gtest.h>
#include <signal.h>

#include <thread>

#include "farm/block_codec.h"
#include "farm/fake_worker.h"
#include "farm/harness.h"
#include "image/bitmap.h"
#include "integrators/integrator.h"
#include "render/image_task.h"
#include "scene/scene.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

TEST(FarmRecovery, KilledMasterResumesTheJobWithTheSameImage) {
    Farm farm("master-restart");
    const std::string scene = writeTestScene(farm.dir() + "/scene", 128, 8);
    const std::string spec = "--spp 160 --seed 21";
    const std::string ref = farm.dir() + "/reference.exr";
    ASSERT_EQ(farm.cli("render " + scene + " -q " + spec + " -o " + ref).first, 0);

    const std::vector<std::string> args = {"--lease-ms", "3000", "--heartbeat-ms", "250", "--checkpoint-ms", "200"};
    farm.startMaster(args);
    farm.startWorker(1);
    farm.startWorker(1);
    const auto [code, output] = farm.cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    const std::string job = std::to_string(id);
    // Killed once some results are in a checkpoint and the rest are still to come.
    ASSERT_TRUE(
        waitUntil([&] { return farm.queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + job) >= 2; }, 120s));
    farm.killMaster();
    const int64_t mergedBefore = farm.queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + job);
    ASSERT_LT(mergedBefore, 18) << "the job finished before the master was killed; make its tasks longer";

    farm.startMaster(args);
    EXPECT_NE(farm.master().log().find("resumed"), std::string::npos) << farm.master().log();
    const v1::Job done = farm.waitForJob(id, 180s);
    ASSERT_EQ(done.state(), v1::JOB_DONE) << done.DebugString() << farm.master().log();
    const auto [fcode, fetched] = farm.cli("fetch " + job + " -o " + farm.dir() + "/farm.exr");
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, farm.dir() + "/farm.exr"));
    // Every task (16 of 8 spp, then 2 of 16: render/image_task.h) merged exactly once, across both lives
    // of the master.
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + job), 18);
    EXPECT_EQ(farm.queryStore("SELECT COUNT(DISTINCT task_idx) FROM merges WHERE job_id = " + job), 18);
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM (SELECT task_idx FROM merges WHERE job_id = " + job +
                              " GROUP BY task_idx HAVING COUNT(*) > 1)"),
              0);
}

TEST(FarmRecovery, LateResultOfASupersededAttemptIsIgnored) {
    Farm farm("late-result");
    const std::string scene = writeTestScene(farm.dir() + "/scene", 24, 8);
    const std::string ref = farm.dir() + "/reference.exr";
    ASSERT_EQ(farm.cli("render " + scene + " -q --spp 8 --seed 2 -o " + ref).first, 0);
    farm.startMaster({"--lease-ms", "500", "--heartbeat-ms", "100"});
    const auto [code, output] = farm.cli("submit " + scene + " --spp 8 --seed 2");
    ASSERT_EQ(code, 0) << output;
    const std::string job = std::to_string(jobIdFrom(output));

    // The task's result, rendered here exactly as a worker renders it.
    auto loaded = loadScene(scene);
    const auto integrator = createIntegrator("path", loaded->integratorProperties(), true);
    const ImageTaskResult result =
        runImageTask(*loaded, dynamic_cast<const SamplingIntegrator &>(*integrator), 2, ImageTask{0, 8}, 1);
    const std::string payload = pf::farm::encodeBlock(result.block);

    FakeWorker slow(farm), fast(farm);
    const auto first = slow.lease();
    ASSERT_TRUE(first);
    // `slow` never renews its lease: the master expires it and gives the task to `fast`.
    ASSERT_TRUE(waitUntil(
        [&] {
            return farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'expired' AND id = " +
                                   std::to_string(first->attempt_id())) == 1;
        },
        30s));
    const auto second = fast.lease();
    ASSERT_TRUE(second);
    EXPECT_EQ(second->task_index(), first->task_index());
    EXPECT_NE(second->attempt_id(), first->attempt_id());
    EXPECT_TRUE(fast.complete(second->attempt_id(), payload).accepted());

    const v1::CompleteReply late = slow.complete(first->attempt_id(), payload);
    EXPECT_FALSE(late.accepted());
    EXPECT_NE(late.reason().find("superseded"), std::string::npos) << late.reason();
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'ignored' AND id = " +
                              std::to_string(first->attempt_id())),
              1);

    const v1::Job done = farm.waitForJob(std::stoll(job), 30s);
    ASSERT_EQ(done.state(), v1::JOB_DONE) << done.DebugString();
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + job), 1);
    const auto [fcode, fetched] = farm.cli("fetch " + job + " -o " + farm.dir() + "/farm.exr");
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, farm.dir() + "/farm.exr"));
    EXPECT_TRUE(farm.master().running());
}

// A worker lists the attempts it holds in every heartbeat until its upload's reply comes back, so a heartbeat can
// reach the master just after the result was accepted. That attempt is done, not lost: the worker logged "lease lost
// (expired or job ended)" for about 1% of the tasks of a healthy 1024² erpt job. One heartbeat later the master
// no longer knows it.
TEST(FarmRecovery, AHeartbeatThatCrossesAnAcceptedResultDoesNotCallItLost) {
    Farm farm("heartbeat-after-result");
    const std::string scene = writeTestScene(farm.dir() + "/scene", 24, 8);
    farm.startMaster({"--lease-ms", "5000", "--heartbeat-ms", "100"});
    const auto [code, output] = farm.cli("submit " + scene + " --spp 8 --seed 2");
    ASSERT_EQ(code, 0) << output;

    auto loaded = loadScene(scene);
    const auto integrator = createIntegrator("path", loaded->integratorProperties(), true);
    const ImageTaskResult result =
        runImageTask(*loaded, dynamic_cast<const SamplingIntegrator &>(*integrator), 2, ImageTask{0, 8}, 1);

    FakeWorker worker(farm);
    const auto task = worker.lease();
    ASSERT_TRUE(task);
    const int64_t attempt = task->attempt_id();
    EXPECT_TRUE(worker.heartbeat({attempt}).empty()) << "a live lease";
    EXPECT_TRUE(worker.complete(attempt, pf::farm::encodeBlock(result.block)).accepted());
    EXPECT_TRUE(worker.heartbeat({attempt}).empty()) << "the heartbeat that crossed the accepted result";
    EXPECT_EQ(worker.heartbeat({attempt}), std::vector<int64_t>{attempt}) << "a heartbeat later";
    EXPECT_EQ(worker.heartbeat({attempt + 1000}), std::vector<int64_t>{attempt + 1000}) << "never leased";
    EXPECT_EQ(farm.waitForJob(jobIdFrom(output), 30s).state(), v1::JOB_DONE);
}

// SIGTERM drains a worker: it finishes and delivers what it holds. When the master is gone, the worker
// stops retrying once the master has been silent for a lease time (by then the tasks are another
// worker's) and exits with code 1, saying what it abandoned, instead of retrying forever. The master is
// killed (connections refused) or stopped (SIGSTOP: a partition, where calls hang rather than fail).
void expectDrainingWorkerGivesUp(const std::string &name, int masterSignal) {
    Farm farm(name);
    // Tasks of 8 spp at 256 x 256 keep one thread busy for a while: the master goes mid-render.
    const std::string scene = writeTestScene(farm.dir() + "/scene", 256, 8);
    farm.startMaster({"--lease-ms", "2000", "--heartbeat-ms", "250"});
    Process &worker = farm.startWorker(1);
    const auto [code, output] = farm.cli("submit " + scene + " --spp 4096 --seed 3");
    ASSERT_EQ(code, 0) << output;
    // The second task: the bundle is cached and the scene loaded, so the worker is rendering.
    const auto renders = [&] {
        const std::string log = worker.log();
        size_t n = 0;
        for (size_t at = 0; (at = log.find("rendering samples", at)) != std::string::npos; ++at) ++n;
        return n;
    };
    ASSERT_TRUE(waitUntil([&] { return renders() >= 2; }, 120s)) << worker.log();
    farm.master().signal(masterSignal);
    // The render ends and its upload starts: it fails at once against a dead master and hangs against
    // a stopped one.
    if (masterSignal == SIGKILL) {
        ASSERT_TRUE(waitUntil([&] { return worker.log().find("retrying the upload") != std::string::npos; }, 120s))
            << worker.log();
    } else {
        std::this_thread::sleep_for(3s);
    }
    const auto signalled = std::chrono::steady_clock::now();
    worker.signal(SIGTERM);
    const auto exitCode = worker.wait(60s);
    ASSERT_TRUE(exitCode) << "the draining worker kept waiting for its master:\n" << worker.log();
    // The render in hand (about a second), a lease time (2 s) without an answer, then at most one
    // backoff step (5 s) or one heartbeat call (0.5 s) and one more call.
    EXPECT_LT(std::chrono::steady_clock::now() - signalled, 20s) << worker.log();
    EXPECT_EQ(*exitCode, 1) << worker.log();
    EXPECT_NE(worker.log().find("result abandoned"), std::string::npos) << worker.log();
    // The task rendering when the master went, and perhaps the one before it (uploads overlap renders).
    EXPECT_NE(worker.log().find("drained without the master: "), std::string::npos) << worker.log();
}

TEST(FarmRecovery, DrainingWorkerExitsWhenItsMasterIsKilled) {
    expectDrainingWorkerGivesUp("drain-master-killed", SIGKILL);
}

TEST(FarmRecovery, DrainingWorkerExitsWhenItsMasterIsSilent) {
    expectDrainingWorkerGivesUp("drain-master-stopped", SIGSTOP);
}

}  // namespace
}  // namespace pf::test::farm
