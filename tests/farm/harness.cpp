#include "farm/harness.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sqlite3.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <thread>

#include "farm/rpc.h"
#include "image/bitmap.h"
#include "support/process.h"
#include "support/render_util.h"

extern char **environ;

namespace pf::test::farm {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

Process::Process(const std::vector<std::string> &argv, const std::string &logFile, const std::string &cwd)
    : logFile_(logFile) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!cwd.empty()) posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
    posix_spawn_file_actions_addopen(&actions, 1, logFile.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    std::vector<char *> args;
    for (const std::string &a : argv) args.push_back(const_cast<char *>(a.c_str()));
    args.push_back(nullptr);
    const int rc = posix_spawn(&pid_, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
}

Process::~Process() {
    if (running()) signal(SIGKILL);
    wait(std::chrono::seconds(10));
}

void Process::signal(int sig) const { ::kill(pid_, sig); }

std::optional<int> Process::wait(std::chrono::milliseconds timeout) {
    waitUntil([&] { return !running(); }, timeout);
    return status_;
}

bool Process::running() {
    if (status_) return false;
    int st = 0;
    if (waitpid(pid_, &st, WNOHANG) != pid_) return true;
    status_ = WIFEXITED(st) ? WEXITSTATUS(st) : -WTERMSIG(st);
    return false;
}

std::string Process::log() const {
    std::ifstream in(logFile_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string writeTestScene(const std::string &dir, int res, int spp) {
    fs::create_directories(dir + "/parts");
    fs::create_directories(dir + "/meshes");
    writeFile(dir, "parts/light.xml", R"(<scene version="0.6.0">
  <emitter type="constant"><spectrum name="radiance" value="0.3"/></emitter>
  <shape type="sphere"><point name="center" x="1.5" y="2.5" z="-1"/><float name="radius" value="0.4"/>
    <emitter type="area"><spectrum name="radiance" value="12"/></emitter></shape>
</scene>
)");
    writeFile(dir, "meshes/floor.obj", "v -3 0 -3\nv 3 0 -3\nv 3 0 3\nv -3 0 3\nf 1 3 2\nf 1 4 3\n");
    return writeFile(dir, "scene.xml",
                     R"(<scene version="0.6.0">
  <default name="res" value=")" +
                         std::to_string(res) + R"("/>
  <integrator type="path"><integer name="maxDepth" value="5"/></integrator>
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="toWorld"><lookat origin="0, 1, -4.5" target="0, 0.6, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sampleCount" value=")" +
                         std::to_string(spp) + R"("/></sampler>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/>
      <rfilter type="gaussian"/></film>
  </sensor>
  <include filename="parts/light.xml"/>
  <shape type="obj"><string name="filename" value="meshes/floor.obj"/>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="0" y="0.7" z="0"/><float name="radius" value="0.7"/>
    <bsdf type="diffuse"/></shape>
</scene>
)");
}

int64_t jobIdFrom(const std::string &submitOutput) {
    std::smatch m;
    if (!std::regex_search(submitOutput, m, std::regex("job (\\d+) submitted"))) return -1;
    return std::stoll(m[1]);
}

bool sameBits(const std::string &exrA, const std::string &exrB) {
    const Bitmap a = readEXR(exrA), b = readEXR(exrB);
    return a.width == b.width && a.height == b.height && a.rgb.size() == b.rgb.size() &&
           std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)) == 0;
}

bool waitUntil(const std::function<bool()> &done, std::chrono::milliseconds timeout) {
    const auto until = std::chrono::steady_clock::now() + timeout;
    for (;;) {
        if (done()) return true;
        if (std::chrono::steady_clock::now() > until) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
}

namespace {
// A port the kernel chose for a socket bound to 127.0.0.1 and closed again.
int unusedPort() {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof addr;
    if (bind(fd, reinterpret_cast<sockaddr *>(&addr), sizeof addr) != 0 ||
        getsockname(fd, reinterpret_cast<sockaddr *>(&addr), &len) != 0) {
        close(fd);
        throw std::runtime_error("no free port");
    }
    close(fd);
    return ntohs(addr.sin_port);
}
}  // namespace

int freePort() {
    // The kernel may hand the same free port to two calls in a row (the first was closed at once); a test
    // that asks twice wants two ports.
    static std::mutex mutex;
    static std::set<int> given;
    const std::lock_guard<std::mutex> lock(mutex);
    for (;;) {
        const int port = unusedPort();
        if (given.insert(port).second) return port;
    }
}

const std::vector<std::string> kFastLeases = {"--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "300"};

void FarmTest::SetUp() {
    farm = std::make_unique<Farm>(::testing::UnitTest::GetInstance()->current_test_info()->name());
}

std::string Farm::embeddedRender(const std::string &scene, const std::string &args, const std::string &name) const {
    const std::string out = dir_ + "/" + name + ".exr";
    const auto [code, output] = cli("render " + scene + " -q " + args + " -o " + out);
    EXPECT_EQ(code, 0) << output;
    return out;
}

pathfarm::v1::Job Farm::submitMatchingEmbedded(const std::string &scene, const std::string &args,
                                               std::string &farmImage, std::string &embeddedImage) const {
    embeddedImage = embeddedRender(scene, args, "embedded");
    farmImage = dir_ + "/farm.exr";
    const auto [code, output] = cli("submit " + scene + " " + args + " --wait -o " + farmImage);
    EXPECT_EQ(code, 0) << output << master_->log();
    if (code != 0) return {};
    EXPECT_TRUE(sameBits(embeddedImage, farmImage));
    pathfarm::v1::Job job = waitForJob(jobIdFrom(output), std::chrono::seconds(10));
    EXPECT_EQ(job.state(), pathfarm::v1::JOB_DONE);
    return job;
}

Farm::Farm(const std::string &name) : dir_(tempDir("farm-" + name)), port_(freePort()), masterData_(dir_ + "/data") {
    std::random_device rd;
    auto token = [&] {
        std::string t;
        for (int i = 0; i < 32; ++i) t += "0123456789abcdef"[rd() % 16];
        return t;
    };
    clientToken_ = token();
    workerToken_ = token();
    writeFile(dir_, "client.token", clientToken_ + "\n");
    writeFile(dir_, "worker.token", workerToken_ + "\n");
}

Process &Farm::startMaster(const std::vector<std::string> &extraArgs) {
    std::vector<std::string> argv = {PATHFARM_MASTER_BIN, "--listen",     address(),         "--data",
                                     masterData_,         "--token-file", clientTokenFile(), "--worker-token-file",
                                     workerTokenFile()};
    argv.insert(argv.end(), extraArgs.begin(), extraArgs.end());
    master_ = std::make_unique<Process>(argv, dir_ + "/master-" + std::to_string(masterStarts_++) + ".log", masterCwd_);
    // Connecting before the port is open would put the channel into reconnect backoff.
    waitUntil([&] { return !master_->running() || master_->log().find("listening on") != std::string::npos; },
              std::chrono::seconds(30));
    const auto stub = clientStub();
    grpc::Status last;
    const bool up = waitUntil(
        [&] {
            v1::ListJobsReply reply;
            if (!master_->running()) return false;
            last = stub->ListJobs(context(clientToken_, 5).get(), v1::ListJobsRequest(), &reply);
            return last.ok();
        },
        std::chrono::seconds(30));
    if (!up) ADD_FAILURE() << "the master did not start (" << last.error_message() << "):\n" << master_->log();
    return *master_;
}

Process &Farm::startWorker(int threads, const std::vector<std::string> &extraArgs) {
    const std::string n = std::to_string(workers_.size());
    std::vector<std::string> argv = {PATHFARM_WORKER_BIN,
                                     "--master",
                                     address(),
                                     "--token-file",
                                     workerTokenFile(),
                                     "--threads",
                                     std::to_string(threads),
                                     "--cache",
                                     dir_ + "/cache-" + n,
                                     "--name",
                                     "worker-" + n};
    argv.insert(argv.end(), extraArgs.begin(), extraArgs.end());
    workers_.push_back(std::make_unique<Process>(argv, dir_ + "/worker-" + n + ".log"));
    return *workers_.back();
}

void Farm::killMaster() {
    master_->signal(SIGKILL);
    master_->wait(std::chrono::seconds(10));
}

std::unique_ptr<v1::ClientService::Stub> Farm::clientStub(int maxMessageBytes) const {
    return v1::ClientService::NewStub(pf::farm::makeChannel(address(), tls_, maxMessageBytes));
}

std::unique_ptr<v1::WorkerService::Stub> Farm::workerStub(int maxMessageBytes) const {
    return v1::WorkerService::NewStub(pf::farm::makeChannel(address(), tls_, maxMessageBytes));
}

std::unique_ptr<grpc::ClientContext> Farm::context(const std::string &token, int timeoutSeconds) const {
    auto ctx = std::make_unique<grpc::ClientContext>();
    if (!token.empty()) pf::farm::setBearer(*ctx, token);
    ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(timeoutSeconds));
    return ctx;
}

std::pair<int, std::string> Farm::cli(const std::string &args) const {
    const ProcessResult r = runCommand("PATHFARM_MASTER=" + address() + " PATHFARM_TOKEN=" + clientToken_ + " " +
                                       PATHFARM_CLI_BIN + " " + args);
    return {r.exitCode, r.output};
}

v1::Job Farm::waitForJob(int64_t id, std::chrono::seconds timeout) const {
    const auto stub = clientStub();
    v1::Job job;
    const bool ended = waitUntil(
        [&] {
            v1::GetJobRequest req;
            req.set_id(id);
            return stub->GetJob(context(clientToken_, 5).get(), req, &job).ok() && job.state() != v1::JOB_QUEUED &&
                   job.state() != v1::JOB_RUNNING;
        },
        timeout);
    if (!ended) ADD_FAILURE() << "job " << id << " did not end in " << timeout.count() << " s: " << job.DebugString();
    return job;
}

int64_t Farm::queryStore(const std::string &sql) const {
    sqlite3 *db = nullptr;
    int64_t value = -1;
    if (sqlite3_open(storePath().c_str(), &db) == SQLITE_OK) {
        sqlite3_busy_timeout(db, 5000);
        sqlite3_stmt *st = nullptr;
        if (sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
            value = sqlite3_column_int64(st, 0);
        else
            ADD_FAILURE() << "store query failed: " << sql << ": " << sqlite3_errmsg(db);
        sqlite3_finalize(st);
    }
    sqlite3_close(db);
    return value;
}

}  // namespace pf::test::farm
