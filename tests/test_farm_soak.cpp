// The soak (issue 18, item 2): a master and three workers, each on a host of its own (network namespaces,
// tests/farm/netns.h; on loopback where they are unavailable) run a queue of jobs of every integrator
// while a chaos loop SIGKILLs workers, stops them (SIGSTOP, later SIGCONT), pulls a worker's cable (netns:
// its link goes down; loopback: SIGSTOP, the closest a single host has) and SIGKILL-restarts the master.
// At the end every job is done with the bits of its embedded render, the store shows every task merged
// exactly once, and the last master's open files and memory are back near what they were at its start.
// Prints the counts: jobs, tasks, kills, stops, cuts, master restarts, re-leases, late results ignored,
// double merges, and the master's peak memory.
// Runs PATHFARM_SOAK_SECONDS of chaos (default 75: the short version `make test` runs); `make soak` runs
// 20 minutes.
#include <gtest/gtest.h>
#include <signal.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include "farm/harness.h"
#include "farm/netns.h"
#include "support/process.h"

namespace pf::test::farm {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

double soakSeconds() {
    const char *s = std::getenv("PATHFARM_SOAK_SECONDS");
    return s ? std::atof(s) : 75.0;
}

// Every integrator, on a 48 x 48 scene, with budgets of a few seconds on one thread.
struct JobCase {
    const char *integrator, *args;
};
const JobCase kCases[] = {
    {"path", "--spp 24"},
    {"volpath", "--spp 16"},
    {"bdpt", "--spp 8"},
    {"pssmlt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4"},
    {"mmlt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4"},
    {"mlt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4"},
    {"erpt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4 -P chainLength=20 -P numChains=0.5"},
    {"mept", "--spp 8 -P luminanceSamples=20000 -P directSamples=4 -P chainLength=20 -P numChains=0.5"},
    {"memlt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4"},
};

// /proc figures of a process: resident memory (KiB) and open descriptors.
int64_t residentKiB(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/status");
    for (std::string line; std::getline(in, line);)
        if (line.rfind("VmRSS:", 0) == 0) return std::atoll(line.c_str() + 6);
    return 0;
}
int64_t openFiles(pid_t pid) {
    std::error_code ec;
    int64_t n = 0;
    for (std::filesystem::directory_iterator it("/proc/" + std::to_string(pid) + "/fd", ec), end; !ec && it != end;
         it.increment(ec))
        ++n;
    return n;
}

class Soak : public ::testing::Test {
protected:
    static constexpr int kWorkers = 3;
    static constexpr int kGrpcPort = 7700;

    void SetUp() override {
        farm = std::make_unique<Farm>("soak");
        scene = writeTestScene(farm->dir() + "/scene", 48, 8);
        if (const std::string reason = NetnsLan::unavailableReason(); reason.empty()) {
            lan = std::make_unique<NetnsLan>("soak");
            masterHost = lan->addHost("master");
            clientHost = lan->addHost("client");
            for (int i = 0; i < kWorkers; ++i) workerHosts.push_back(lan->addHost("worker-" + std::to_string(i)));
            address = masterHost.address + ":" + std::to_string(kGrpcPort);
            std::printf("soak: %d workers on hosts of their own (network namespaces)\n", kWorkers);
        } else {
            address = farm->address();
            std::printf("soak: on loopback (network namespaces unavailable: %s); a cut link is a SIGSTOP\n",
                        reason.c_str());
        }
        workers.resize(kWorkers);
        for (int i = 0; i < kWorkers; ++i) startWorker(i);
    }

    std::vector<std::string> on(const NetnsLan::Host &host, const std::vector<std::string> &argv) const {
        return lan ? lan->exec(host, argv) : argv;
    }

    void startMaster() {
        std::vector<std::string> argv = {PATHFARM_MASTER_BIN,
                                         "--listen",
                                         address,
                                         "--data",
                                         farm->dir() + "/data",
                                         "--token-file",
                                         farm->clientTokenFile(),
                                         "--worker-token-file",
                                         farm->workerTokenFile()};
        argv.insert(argv.end(), kFastLeases.begin(), kFastLeases.end());
        master = std::make_unique<Process>(on(masterHost, argv),
                                           farm->dir() + "/master-" + std::to_string(masterStarts++) + ".log");
        ASSERT_TRUE(waitUntil([&] { return master->log().find("listening on") != std::string::npos; }, 60s))
            << master->log();
    }

    void startWorker(int i) {
        const std::string name = "worker-" + std::to_string(i);
        workers[i] = std::make_unique<Process>(
            on(lan ? workerHosts[i] : masterHost,
               {PATHFARM_WORKER_BIN, "--master", address, "--token-file", farm->workerTokenFile(), "--threads", "1",
                "--cache", farm->dir() + "/cache-" + name, "--name", name}),
            farm->dir() + "/" + name + "-" + std::to_string(workerStarts++) + ".log");
    }

    std::pair<int, std::string> cli(const std::string &args) const {
        const std::string line = "PATHFARM_MASTER=" + address + " PATHFARM_TOKEN=" + farm->clientToken() + " " +
                                 PATHFARM_CLI_BIN + " " + args;
        const ProcessResult r = runCommand(lan ? lan->shell(clientHost, line) : line);
        return {r.exitCode, r.output};
    }

    int64_t store(const std::string &sql) const { return farm->queryStore(sql); }

    std::unique_ptr<NetnsLan> lan;  // declared first: deleted after the processes left its namespaces
    std::unique_ptr<Farm> farm;
    NetnsLan::Host masterHost, clientHost;
    std::vector<NetnsLan::Host> workerHosts;
    std::string address, scene;
    std::unique_ptr<Process> master;
    std::vector<std::unique_ptr<Process>> workers;
    int masterStarts = 0, workerStarts = 0;
};

TEST_F(Soak, ChaosLosesNothingAndMergesNothingTwice) {
    const double seconds = soakSeconds();
    const auto start = Clock::now();
    const auto elapsed = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    startMaster();
    // Master restarts until three quarters of the time; the last master then runs to the end, and its
    // descriptors and memory at the end are compared with those at its start.
    const double restartEvery = std::max(20.0, seconds / 8);
    double nextRestart = restartEvery;
    std::mt19937 rng(18);
    const auto uniform = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };

    std::map<int64_t, std::string> jobs;  // id -> spec
    int submitted = 0, kills = 0, stops = 0, cuts = 0, restarts = 0;
    int64_t peakKiB = 0, startKiB = 0, startFds = 0;
    // The last master's figures at its start, once the workers are back (3 s after it started).
    double measureAt = elapsed() + 3;
    // What the chaos undoes later: SIGCONT or link up of worker i at a time.
    struct Undo {
        double at;
        int worker;
        bool link;
    };
    std::vector<Undo> undo;
    const auto restore = [&](const Undo &u) {
        if (u.link) {
            lan->setLink(workerHosts[u.worker], true);
        } else {
            workers[u.worker]->signal(SIGCONT);
        }
    };
    const auto busy = [&](int w) {
        return std::any_of(undo.begin(), undo.end(), [&](const Undo &u) { return u.worker == w; });
    };

    while (elapsed() < seconds) {
        std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(uniform(500, 2500))));
        const double now = elapsed();
        for (auto it = undo.begin(); it != undo.end();) {
            if (it->at <= now) {
                restore(*it);
                it = undo.erase(it);
            } else {
                ++it;
            }
        }
        // Keep three jobs queued or running.
        if (store("SELECT COUNT(*) FROM jobs WHERE state IN (1, 2)") < 3) {
            const JobCase &c = kCases[submitted % std::size(kCases)];
            const std::string spec = std::string("--integrator ") + c.integrator + " " + c.args + " --seed " +
                                     std::to_string(1 + submitted / std::size(kCases) % 2) + " -P maxDepth=4";
            const auto [code, output] = cli("submit " + scene + " " + spec);
            if (code == 0) {  // else the master is down: the next round submits it
                jobs[jobIdFrom(output)] = spec;
                ++submitted;
            }
        }
        if (now >= nextRestart && now < 0.75 * seconds) {
            master->signal(SIGKILL);
            master->wait(10s);
            startMaster();
            ++restarts;
            nextRestart += restartEvery;
            measureAt = elapsed() + 3;
            continue;
        }
        if (measureAt > 0 && now >= measureAt) {
            startKiB = residentKiB(master->pid());
            startFds = openFiles(master->pid());
            measureAt = 0;
        }
        const int w = std::uniform_int_distribution<int>(0, kWorkers - 1)(rng);
        if (busy(w)) continue;
        switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
            case 0:
            case 1:
                workers[w]->signal(SIGKILL);
                workers[w]->wait(10s);
                startWorker(w);
                ++kills;
                break;
            case 2:
            case 3:
                workers[w]->signal(SIGSTOP);
                undo.push_back({now + uniform(0.5, 4), w, false});
                ++stops;
                break;
            case 4:
                if (lan) {
                    lan->setLink(workerHosts[w], false);
                    undo.push_back({now + uniform(1, 5), w, true});
                } else {
                    workers[w]->signal(SIGSTOP);
                    undo.push_back({now + uniform(1, 5), w, false});
                }
                ++cuts;
                break;
            default:
                break;  // a quiet round
        }
        peakKiB = std::max(peakKiB, residentKiB(master->pid()));
    }
    for (const Undo &u : undo) restore(u);

    // Every job done: the farm is left alone now.
    for (const auto &[id, spec] : jobs) {
        const std::string job = std::to_string(id);
        const bool ended = waitUntil(
            [&] { return store("SELECT state FROM jobs WHERE id = " + job) >= 3 || !master->running(); }, 600s);
        ASSERT_TRUE(ended && master->running()) << "job " << job << " did not end:\n" << master->log();
        ASSERT_EQ(store("SELECT state FROM jobs WHERE id = " + job), 3) << "job " << job << " " << spec;
    }
    std::this_thread::sleep_for(2s);  // the reaper closes the last films
    const int64_t endKiB = residentKiB(master->pid()), endFds = openFiles(master->pid());
    peakKiB = std::max(peakKiB, endKiB);

    // Bit for bit the embedded render of the same spec (one reference per distinct spec).
    std::map<std::string, std::string> references;
    int equal = 0;
    for (const auto &[id, spec] : jobs) {
        SCOPED_TRACE("job " + std::to_string(id) + ": " + spec);
        if (!references.count(spec))
            references[spec] = farm->embeddedRender(scene, spec, "ref-" + std::to_string(references.size()));
        const std::string out = farm->dir() + "/job-" + std::to_string(id) + ".exr";
        const auto [code, output] = cli("fetch " + std::to_string(id) + " -o " + out);
        ASSERT_EQ(code, 0) << output;
        const bool same = sameBits(references[spec], out);
        EXPECT_TRUE(same);
        equal += same;
        const std::string job = std::to_string(id);
        EXPECT_EQ(store("SELECT COUNT(DISTINCT task_idx) FROM merges WHERE job_id = " + job),
                  store("SELECT COUNT(*) FROM tasks WHERE job_id = " + job));
        EXPECT_EQ(store("SELECT COUNT(*) FROM tasks WHERE state != 'merged' AND job_id = " + job), 0);
    }
    const int64_t doubleMerges =
        store("SELECT COUNT(*) FROM (SELECT 1 FROM merges GROUP BY job_id, task_idx HAVING COUNT(*) > 1)");
    const int64_t tasks = store("SELECT COUNT(*) FROM tasks");
    const int64_t releases = store("SELECT COUNT(*) FROM attempts") - tasks;
    const int64_t ignored = store("SELECT COUNT(*) FROM attempts WHERE state = 'ignored'");
    std::printf(
        "soak: %.0f s of chaos (%s), %zu jobs of %zu integrators, %lld tasks; worker kills %d, stops %d, cut links "
        "%d, master restarts %d; re-leases %lld, late results ignored %lld; images equal %d of %zu; double merges "
        "%lld; last master: RSS %lld -> %lld KiB (peak over the soak %lld KiB), open files %lld -> %lld\n",
        seconds, lan ? "network namespaces" : "loopback", jobs.size(), std::size(kCases), static_cast<long long>(tasks),
        kills, stops, cuts, restarts, static_cast<long long>(releases), static_cast<long long>(ignored), equal,
        jobs.size(), static_cast<long long>(doubleMerges), static_cast<long long>(startKiB),
        static_cast<long long>(endKiB), static_cast<long long>(peakKiB), static_cast<long long>(startFds),
        static_cast<long long>(endFds));
    EXPECT_EQ(doubleMerges, 0);
    EXPECT_GE(restarts, 2);
    EXPECT_GT(kills, 0);
    // Descriptors: a few connections may come and go. Memory: the master keeps up to its malloc trim
    // threshold (256 MiB, master/main.cpp) of freed heap rather than returning it, so only growth beyond
    // that is a leak.
    EXPECT_LE(endFds, startFds + 8);
    EXPECT_LE(endKiB, startKiB + (256 + 64) * 1024);
}

}  // namespace
}  // namespace pf::test::farm
