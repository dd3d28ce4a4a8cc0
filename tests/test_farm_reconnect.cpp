// The CLI across a master restart, with real processes: `submit --wait`, `watch` and `fetch` reconnect
// to a master that is SIGKILLed and restarted and finish their work with the exact image; a master whose
// data directory was given relative to another working directory resumes its job; and what reconnecting
// must not wait for (an unknown job, a refused token, a master that stays away) ends the command.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>

#include "farm/harness.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

const std::string kSpec = "--spp 160 --seed 21";

class FarmReconnect : public FarmTest {};

// `pathfarm ARGS` for this farm as a process of its own, so that the test can restart the master
// while the command runs.
std::unique_ptr<Process> startCli(const Farm &farm, const std::vector<std::string> &args, const std::string &log) {
    std::vector<std::string> argv = {PATHFARM_CLI_BIN};
    argv.insert(argv.end(), args.begin(), args.end());
    argv.insert(argv.end(), {"--master", farm.address(), "--token-file", farm.clientTokenFile()});
    return std::make_unique<Process>(argv, farm.dir() + "/" + log + ".log");
}

int64_t submit(const Farm &farm, const std::string &scene) {
    const auto [code, output] = farm.cli("submit " + scene + " " + kSpec);
    EXPECT_EQ(code, 0) << output;
    return jobIdFrom(output);
}

// SIGKILLs the master once job `id` has merged results in a checkpoint and restarts it. The worker is
// stopped across the restart, so that the job is still running however fast it renders.
void restartMasterMidJob(Farm &farm, Process &worker, int64_t id) {
    const std::string merges = "SELECT COUNT(*) FROM merges WHERE job_id = " + std::to_string(id);
    ASSERT_TRUE(waitUntil([&] { return farm.queryStore(merges) >= 2; }, 120s));
    worker.signal(SIGSTOP);
    farm.killMaster();
    ASSERT_LT(farm.queryStore(merges), 18) << "the job ended before the master was killed";
    farm.startMaster(kFastLeases);
    EXPECT_NE(farm.master().log().find("resumed"), std::string::npos) << farm.master().log();
    worker.signal(SIGCONT);
}

// The command's exit code, failing the test if it does not end within `timeout`.
int exitCode(Process &p, std::chrono::seconds timeout) {
    const std::optional<int> code = p.wait(timeout);
    EXPECT_TRUE(code.has_value()) << "still running after " << timeout.count() << " s:\n" << p.log();
    return code.value_or(-1);
}

TEST_F(FarmReconnect, SubmitWaitWatchAndFetchRideOutMasterRestarts) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 128, 8);
    const std::string ref = farm->embeddedRender(scene, kSpec, "reference");
    farm->startMaster(kFastLeases);
    Process &worker = farm->startWorker(1);

    const std::string waited = farm->dir() + "/waited.exr";
    auto submitter =
        startCli(*farm, {"submit", scene, "--spp", "160", "--seed", "21", "--wait", "-o", waited}, "submit");
    int64_t id = -1;
    ASSERT_TRUE(waitUntil([&] { return (id = jobIdFrom(submitter->log())) > 0; }, 60s)) << submitter->log();
    auto watcher = startCli(*farm, {"watch", std::to_string(id)}, "watch");
    restartMasterMidJob(*farm, worker, id);

    EXPECT_EQ(exitCode(*submitter, 180s), 0) << submitter->log();
    EXPECT_NE(submitter->log().find("reconnecting for up to 120 s"), std::string::npos) << submitter->log();
    EXPECT_TRUE(sameBits(ref, waited));
    EXPECT_EQ(exitCode(*watcher, 60s), 0) << watcher->log();
    EXPECT_NE(watcher->log().find("reconnecting"), std::string::npos) << watcher->log();
    EXPECT_NE(watcher->log().find("done 100.0%"), std::string::npos) << watcher->log();

    // A fetch that starts while the master is down gets the image once it is back.
    farm->killMaster();
    const std::string fetched = farm->dir() + "/fetched.exr";
    auto fetcher = startCli(*farm, {"fetch", std::to_string(id), "-o", fetched}, "fetch");
    ASSERT_TRUE(waitUntil([&] { return fetcher->log().find("reconnecting") != std::string::npos; }, 60s))
        << fetcher->log();
    farm->startMaster(kFastLeases);
    EXPECT_EQ(exitCode(*fetcher, 60s), 0) << fetcher->log();
    EXPECT_TRUE(sameBits(ref, fetched));
}

TEST_F(FarmReconnect, MasterWithARelativeDataDirResumesFromAnotherWorkingDirectory) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 128, 8);
    const std::string ref = farm->embeddedRender(scene, kSpec, "reference");
    farm->setMasterDirectory(farm->dir(), "data");
    farm->startMaster(kFastLeases);
    Process &worker = farm->startWorker(1);
    const int64_t id = submit(*farm, scene);

    const std::string elsewhere = farm->dir() + "/elsewhere";
    std::filesystem::create_directories(elsewhere);
    farm->setMasterDirectory(elsewhere, "../data");
    restartMasterMidJob(*farm, worker, id);
    const v1::Job done = farm->waitForJob(id, 180s);
    ASSERT_EQ(done.state(), v1::JOB_DONE) << done.DebugString() << farm->master().log();
    const auto [code, output] = farm->cli("fetch " + std::to_string(id) + " -o " + farm->dir() + "/farm.exr");
    ASSERT_EQ(code, 0) << output;
    EXPECT_TRUE(sameBits(ref, farm->dir() + "/farm.exr"));
}

TEST_F(FarmReconnect, ReconnectingEndsOnErrorsThatRepeatAndWhenItsTimeIsUp) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 16, 1);
    farm->startMaster();
    const std::string id = std::to_string(submit(*farm, scene));  // no worker: it stays queued

    // Asking again cannot help with an unknown job or a refused token: no reconnecting.
    const auto [unknownCode, unknown] = farm->cli("watch 99");
    EXPECT_NE(unknownCode, 0);
    EXPECT_NE(unknown.find("error: watching job 99: no job 99"), std::string::npos) << unknown;
    EXPECT_EQ(unknown.find("reconnecting"), std::string::npos) << unknown;
    const auto [refusedCode, refused] =
        farm->cli("fetch " + id + " -o " + farm->dir() + "/refused.exr --token-file " + farm->workerTokenFile());
    EXPECT_NE(refusedCode, 0);
    EXPECT_NE(refused.find("wrong bearer token"), std::string::npos) << refused;
    EXPECT_EQ(refused.find("reconnecting"), std::string::npos) << refused;

    // A master that does not come back within --reconnect-timeout: a clear error, non-zero exit. It is
    // stopped with SIGTERM: its shutdown cancels the watch, which is no reason to give up either.
    auto watcher = startCli(*farm, {"watch", id, "--reconnect-timeout", "2"}, "watch");
    ASSERT_TRUE(waitUntil([&] { return watcher->log().find("queued") != std::string::npos; }, 30s)) << watcher->log();
    farm->master().signal(SIGTERM);
    farm->master().wait(30s);
    EXPECT_EQ(exitCode(*watcher, 60s), 1) << watcher->log();
    EXPECT_NE(watcher->log().find("reconnecting for up to 2 s"), std::string::npos) << watcher->log();
    EXPECT_NE(watcher->log().find("error: watching job " + id + ": master still unreachable after 2 s"),
              std::string::npos)
        << watcher->log();

    // 0 turns reconnecting off: the first failure ends the command.
    const auto [offCode, off] = farm->cli("watch " + id + " --reconnect-timeout 0");
    EXPECT_EQ(offCode, 1);
    EXPECT_NE(off.find("error: watching job " + id + ": "), std::string::npos) << off;
    EXPECT_EQ(off.find("reconnecting"), std::string::npos) << off;
}

}  // namespace
}  // namespace pf::test::farm
