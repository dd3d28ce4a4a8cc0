// The farm across hosts, without containers: a master, two workers and a client, each in its own network
// namespace on a bridged private /24 (tests/farm/netns.h). The master listens on its host's address, not
// on loopback, so every call crosses veth links and a bridge as it would cross a LAN. The image equals the
// embedded render bit for bit, also when one worker's cable is pulled in the middle of the job.
// Needs root with CAP_NET_ADMIN; skipped, saying why, without it.
#include <gtest/gtest.h>
#include <httplib.h>

#include <nlohmann/json.hpp>

#include "farm/harness.h"
#include "farm/netns.h"
#include "support/process.h"

namespace pf::test::farm {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

constexpr int kGrpcPort = 7700, kHttpPort = 8080;

class FarmNetns : public ::testing::Test {
protected:
    void SetUp() override {
        const std::string reason = NetnsLan::unavailableReason();
        if (!reason.empty()) GTEST_SKIP() << "network namespaces unavailable: " << reason;
        const std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
        farm = std::make_unique<Farm>("netns-" + name);  // its directory and tokens; its loopback port is unused
        lan = std::make_unique<NetnsLan>(name.substr(0, 8));
        masterHost = lan->addHost("master");
        workerHosts = {lan->addHost("worker-a"), lan->addHost("worker-b")};
        clientHost = lan->addHost("client");
        scene = writeTestScene(farm->dir() + "/scene", 64, 8);
    }

    std::string masterAddress() const { return masterHost.address + ":" + std::to_string(kGrpcPort); }

    void startFarm() {
        master = std::make_unique<Process>(
            lan->exec(masterHost,
                      {PATHFARM_MASTER_BIN, "--listen", masterAddress(), "--http",
                       masterHost.address + ":" + std::to_string(kHttpPort), "--data", farm->dir() + "/data",
                       "--token-file", farm->clientTokenFile(), "--worker-token-file", farm->workerTokenFile(),
                       "--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "300"}),
            farm->dir() + "/master.log");
        ASSERT_TRUE(waitUntil([&] { return get("/readyz").first == 200 || !master->running(); }, 30s) &&
                    master->running())
            << "the master did not come up on " << masterHost.address << ":\n"
            << master->log();
        for (const NetnsLan::Host &h : workerHosts)
            workers.push_back(std::make_unique<Process>(
                lan->exec(h, {PATHFARM_WORKER_BIN, "--master", masterAddress(), "--token-file", farm->workerTokenFile(),
                              "--threads", "1", "--cache", farm->dir() + "/cache-" + h.name, "--name", h.name}),
                farm->dir() + "/" + h.name + ".log"));
        ASSERT_TRUE(waitUntil([&] { return workersJson().size() == workerHosts.size(); }, 30s))
            << "the workers did not register from their hosts:\n"
            << workers[0]->log() << workers[1]->log();
    }

    // An HTTP GET on the master's status port from the client's host: status and body (0 if unreachable).
    std::pair<int, std::string> get(const std::string &path) const {
        std::pair<int, std::string> out{0, ""};
        lan->runIn(clientHost, [&] {
            httplib::Client http(masterHost.address, kHttpPort);
            http.set_connection_timeout(2, 0);
            http.set_read_timeout(5, 0);
            if (const auto res = http.Get(path)) out = {res->status, res->body};
        });
        return out;
    }
    json workersJson() const {
        const auto [status, body] = get("/api/v1/workers");
        return status == 200 ? json::parse(body).value("workers", json::array()) : json::array();
    }
    json workerNamed(const std::string &name) const {
        for (const json &w : workersJson())
            if (w.value("name", "") == name) return w;
        return json::object();
    }
    json job(int64_t id) const {
        const auto [status, body] = get("/api/v1/jobs/" + std::to_string(id));
        return status == 200 ? json::parse(body) : json::object();
    }

    // The `pathfarm` CLI run on the client's host against the master's LAN address.
    std::pair<int, std::string> cli(const std::string &args) const {
        const ProcessResult r = runCommand(lan->shell(clientHost, "PATHFARM_MASTER=" + masterAddress() +
                                                                      " PATHFARM_TOKEN=" + farm->clientToken() + " " +
                                                                      PATHFARM_CLI_BIN + " " + args));
        return {r.exitCode, r.output};
    }

    // The embedded render of the same spec, on the test's own host.
    std::string reference(const std::string &spec) const {
        const std::string out = farm->dir() + "/reference.exr";
        const ProcessResult r =
            runCommand(std::string(PATHFARM_CLI_BIN) + " render " + scene + " -q " + spec + " -o " + out);
        EXPECT_EQ(r.exitCode, 0) << r.output;
        return out;
    }

    std::string logs() const {
        std::string all = "master:\n" + master->log();
        for (size_t i = 0; i < workers.size(); ++i) all += workerHosts[i].name + ":\n" + workers[i]->log();
        return all;
    }

    // Declared first so that it goes last: the processes leave their namespaces before these are deleted.
    std::unique_ptr<NetnsLan> lan;
    std::unique_ptr<Farm> farm;
    NetnsLan::Host masterHost, clientHost;
    std::vector<NetnsLan::Host> workerHosts;
    std::string scene;
    std::unique_ptr<Process> master;
    std::vector<std::unique_ptr<Process>> workers;
};

TEST_F(FarmNetns, WorkersOnTwoHostsRenderTheEmbeddedImage) {
    const std::string spec = "--spp 48 --seed 5 -P maxDepth=4";
    const std::string ref = reference(spec);
    ASSERT_NO_FATAL_FAILURE(startFarm());

    // The master saw each worker arrive from its own host's address, not from loopback.
    for (const NetnsLan::Host &h : workerHosts) {
        const std::string peer = workerNamed(h.name).value("peer", "");
        EXPECT_EQ(peer.rfind("ipv4:" + h.address + ":", 0), 0u) << h.name << " came from '" << peer << "'";
    }

    const std::string out = farm->dir() + "/farm.exr";
    const auto [code, output] = cli("submit " + scene + " " + spec + " --wait -o " + out);
    ASSERT_EQ(code, 0) << output << logs();
    EXPECT_TRUE(sameBits(ref, out)) << "the farm's image differs from the embedded render";
    const int64_t id = jobIdFrom(output);
    const json j = job(id);
    EXPECT_EQ(j.value("state", ""), "JOB_DONE") << j.dump();
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + std::to_string(id)),
              std::stoll(j["tasks"].value("total", "0")));
}

TEST_F(FarmNetns, AJobCompletesWhenAWorkersLinkGoesDownMidJob) {
    const std::string spec = "--spp 256 --seed 9 -P maxDepth=4";
    const std::string ref = reference(spec);
    ASSERT_NO_FATAL_FAILURE(startFarm());
    const auto [code, output] = cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);

    // Pull worker-b's cable while it holds a lease: that task can only be finished by worker-a.
    const NetnsLan::Host victim = workerHosts[1];
    ASSERT_TRUE(waitUntil([&] { return !workerNamed(victim.name).value("attempt_ids", json::array()).empty(); }, 30s))
        << "worker-b never held a lease:\n"
        << logs();
    const json before = job(id);
    ASSERT_EQ(before.value("state", ""), "JOB_RUNNING") << before.dump();
    lan->setLink(victim, false);

    ASSERT_TRUE(waitUntil([&] { return job(id).value("state", "") == "JOB_DONE"; }, 60s)) << job(id).dump() << "\n"
                                                                                          << logs();
    const std::string out = farm->dir() + "/farm.exr";
    const auto [fetchCode, fetched] = cli("fetch " + std::to_string(id) + " -o " + out);
    ASSERT_EQ(fetchCode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, out)) << "the farm's image differs from the embedded render";

    // The master stopped hearing from worker-b, and every task was merged exactly once.
    EXPECT_TRUE(waitUntil([&] { return workerNamed(victim.name).value("state", "") == "WORKER_LOST"; }, 10s))
        << workerNamed(victim.name).dump();
    const json done = job(id);
    EXPECT_GT(std::stoll(workerNamed(workerHosts[0].name).value("tasks_completed", "0")), 0);
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + std::to_string(id)),
              std::stoll(done["tasks"].value("total", "0")));
    std::printf("worker-b cut at %s of %s tasks merged; %s attempts expired\n",
                before["tasks"].value("merged", "0").c_str(), done["tasks"].value("total", "0").c_str(),
                done["tasks"].value("expired_attempts", "0").c_str());
}

}  // namespace
}  // namespace pf::test::farm
