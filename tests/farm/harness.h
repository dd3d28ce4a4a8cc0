// Real processes on loopback for the farm tests: a master and workers started from their binaries with
// their own token files and data directories, killed with real signals, and a gRPC client to talk to
// the master the way the CLI does.
#pragma once
#include <gtest/gtest.h>
#include <sys/types.h>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "farm/rpc.h"
#include "pathfarm/v1/client.grpc.pb.h"
#include "pathfarm/v1/worker.grpc.pb.h"

namespace pf::test::farm {

// A child process whose output goes to a log file, running in `cwd` ("": the test's own). The destructor
// kills (SIGKILL) and reaps it.
class Process {
public:
    Process(const std::vector<std::string> &argv, const std::string &logFile, const std::string &cwd = "");
    ~Process();
    Process(const Process &) = delete;
    Process &operator=(const Process &) = delete;

    pid_t pid() const { return pid_; }
    void signal(int sig) const;
    // The exit code once the process ended within `timeout`; -signal if a signal ended it.
    std::optional<int> wait(std::chrono::milliseconds timeout);
    bool running();
    std::string log() const;

private:
    pid_t pid_ = -1;
    std::optional<int> status_;
    std::string logFile_;
};

// Writes the farm tests' scene into `dir`: scene.xml, which includes parts/light.xml and loads
// meshes/floor.obj (so that bundles carry more than one file), with $res pixels square and `spp`
// samples per pixel by default. Returns the scene's path.
std::string writeTestScene(const std::string &dir, int res, int spp);

// The job id in the output of `pathfarm submit`, or -1.
int64_t jobIdFrom(const std::string &submitOutput);

// Pixels of two images are the same bits.
bool sameBits(const std::string &exrA, const std::string &exrB);

// Polls `done` every 20 ms until it holds or `timeout` passes.
bool waitUntil(const std::function<bool()> &done, std::chrono::milliseconds timeout);

// A port on 127.0.0.1 that was free a moment ago.
int freePort();

// Master flags for tests that kill processes: short leases, so that a killed worker is noticed within a
// second or two, and frequent checkpoints.
extern const std::vector<std::string> kFastLeases;

// One farm: a directory with token files, a master address, and the processes of the test.
class Farm {
public:
    explicit Farm(const std::string &name);
    const std::string &dir() const { return dir_; }
    std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
    const std::string &clientToken() const { return clientToken_; }
    const std::string &workerToken() const { return workerToken_; }
    std::string clientTokenFile() const { return dir_ + "/client.token"; }
    std::string workerTokenFile() const { return dir_ + "/worker.token"; }
    std::string storePath() const { return dir_ + "/data/store.sqlite"; }

    // TLS files the test's own stubs use from now on (the processes get theirs as arguments).
    void useTls(const pf::farm::TlsFiles &tls) { tls_ = tls; }
    // The masters started from now on run in `cwd` with `--data data` as given, which must name this
    // farm's data directory from there (by default: in the test's directory, with an absolute path).
    void setMasterDirectory(const std::string &cwd, const std::string &data) {
        masterCwd_ = cwd;
        masterData_ = data;
    }

    // Starts the master on this farm's port and data directory and waits until it serves.
    Process &startMaster(const std::vector<std::string> &extraArgs = {});
    Process &startWorker(int threads, const std::vector<std::string> &extraArgs = {});
    Process &master() { return *master_; }
    void killMaster();

    // A stub of the client service, and a context carrying `token` (default: the client token).
    std::unique_ptr<pathfarm::v1::ClientService::Stub> clientStub(int maxMessageBytes = 4 << 20) const;
    std::unique_ptr<pathfarm::v1::WorkerService::Stub> workerStub(int maxMessageBytes = 4 << 20) const;
    std::unique_ptr<grpc::ClientContext> context(const std::string &token, int timeoutSeconds = 30) const;

    // The `pathfarm` CLI with PATHFARM_MASTER and PATHFARM_TOKEN set for this farm: output and exit code.
    std::pair<int, std::string> cli(const std::string &args) const;
    // The embedded render `pathfarm render SCENE -q ARGS`, the reference a farm job's image must equal, into
    // DIR/NAME.exr; returns its path and fails the test if the render fails.
    std::string embeddedRender(const std::string &scene, const std::string &args, const std::string &name) const;
    // Waits until the job is done (or failed/cancelled) and returns it; fails the test on timeout.
    pathfarm::v1::Job waitForJob(int64_t id, std::chrono::seconds timeout) const;
    // `pathfarm submit SCENE ARGS --wait` on the running farm, whose image must equal the embedded render of the
    // same ARGS bit for bit (the test fails otherwise, and if the job does not end done); returns the job's
    // record, its image in `farmImage` and the embedded one's in `embeddedImage` (both in this farm's directory).
    pathfarm::v1::Job submitMatchingEmbedded(const std::string &scene, const std::string &args, std::string &farmImage,
                                             std::string &embeddedImage) const;

    // One SQL query on the master's store, returning the first column of the first row.
    int64_t queryStore(const std::string &sql) const;

private:
    std::string dir_;
    int port_;
    std::string clientToken_, workerToken_;
    pf::farm::TlsFiles tls_;
    std::string masterCwd_, masterData_;
    std::unique_ptr<Process> master_;
    std::vector<std::unique_ptr<Process>> workers_;
    int masterStarts_ = 0;
};

// A fixture with one farm per test, named after the test.
class FarmTest : public ::testing::Test {
protected:
    void SetUp() override;
    std::unique_ptr<Farm> farm;
};

}  // namespace pf::test::farm
