#include "embedded_farm.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <thread>
#include <vector>

namespace pf::client {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;
using Clock = std::chrono::steady_clock;

namespace {

// 256 bits from the system's entropy source, as hex.
std::string randomToken() {
    std::random_device rd;
    std::string token;
    char hex[9];
    for (int i = 0; i < 8; ++i) {
        std::snprintf(hex, sizeof hex, "%08x", rd());
        token += hex;
    }
    return token;
}

void writeSecret(const fs::path &path, const std::string &text) {
    std::ofstream(path) << text << "\n";
    fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
}

std::string readLog(const fs::path &path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

// Starts `argv` with stdout and stderr going to `log`. The child gets SIGTERM when this process dies,
// so an interrupted comparison leaves no farm behind.
pid_t spawn(const std::vector<std::string> &argv, const fs::path &log) {
    std::vector<char *> args;
    for (const std::string &a : argv) args.push_back(const_cast<char *>(a.c_str()));
    args.push_back(nullptr);
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw std::runtime_error("cannot start " + argv[0]);
    if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGTERM);
        if (getppid() != parent) _exit(127);
        const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
        if (fd >= 0) {
            dup2(fd, STDOUT_FILENO);
            dup2(fd, STDERR_FILENO);
        }
        execv(args[0], args.data());
        _exit(127);
    }
    return pid;
}

bool exited(pid_t pid) {
    int status = 0;
    return waitpid(pid, &status, WNOHANG) == pid;
}

}  // namespace

EmbeddedFarm::EmbeddedFarm(int threads) {
    const fs::path bin = fs::read_symlink("/proc/self/exe").parent_path();
    const fs::path masterBin = bin / "pathfarm-master", workerBin = bin / "pathfarm-worker";
    for (const fs::path &p : {masterBin, workerBin})
        if (access(p.c_str(), X_OK) != 0)
            throw std::runtime_error("the embedded farm needs " + p.string() + " (beside pathfarm); give --master");
    std::string tmpl = (fs::temp_directory_path() / "pathfarm-compare-XXXXXX").string();
    if (!mkdtemp(tmpl.data())) throw std::runtime_error("cannot create a directory for the embedded farm");
    dir_ = tmpl;
    const fs::path dir(dir_);
    const std::string clientToken = randomToken(), workerToken = randomToken();
    writeSecret(dir / "client.token", clientToken);
    writeSecret(dir / "worker.token", workerToken);

    const auto fail = [&](const std::string &what) {
        const std::string logs = "\n--- master log ---\n" + readLog(dir / "master.log") + "--- worker log ---\n" +
                                 readLog(dir / "worker.log");
        stop(worker_);
        stop(master_);
        std::error_code ec;
        fs::remove_all(dir_, ec);
        throw std::runtime_error("embedded farm: " + what + logs);
    };
    // Port 0: the master binds a free port and logs it, so no port is guessed and raced for.
    master_ = spawn({masterBin.string(), "--listen", "127.0.0.1:0", "--data", (dir / "data").string(), "--token-file",
                     (dir / "client.token").string(), "--worker-token-file", (dir / "worker.token").string()},
                    dir / "master.log");
    const std::regex listening(R"(listening on \S+ \(port (\d+)\))");
    std::smatch m;
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    std::string log;
    while (!std::regex_search(log = readLog(dir / "master.log"), m, listening)) {
        if (exited(master_)) {
            master_ = -1;
            fail("the master exited at start");
        }
        if (Clock::now() > deadline) fail("the master did not start listening within 30 s");
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    connection_.master = "127.0.0.1:" + m[1].str();
    connection_.tokenFile = (dir / "client.token").string();

    std::vector<std::string> workerArgs = {workerBin.string(),
                                           "--master",
                                           connection_.master,
                                           "--token-file",
                                           (dir / "worker.token").string(),
                                           "--cache",
                                           (dir / "cache").string(),
                                           "--name",
                                           "embedded"};
    if (threads > 0) workerArgs.insert(workerArgs.end(), {"--threads", std::to_string(threads)});
    worker_ = spawn(workerArgs, dir / "worker.log");
    const auto stub = v1::ClientService::NewStub(connection_.channel());
    while (true) {
        v1::ListWorkersReply reply;
        if (stub->ListWorkers(connection_.context(5).get(), v1::ListWorkersRequest(), &reply).ok())
            for (const v1::WorkerInfo &w : reply.workers())
                if (w.state() != v1::WORKER_LOST) return;
        if (exited(worker_)) {
            worker_ = -1;
            fail("the worker exited at start");
        }
        if (Clock::now() > deadline) fail("the worker did not register within 30 s");
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
}

void EmbeddedFarm::stop(pid_t &pid) {
    if (pid <= 0) return;
    kill(pid, SIGTERM);
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (!exited(pid)) {
        if (Clock::now() > deadline) {
            kill(pid, SIGKILL);
            waitpid(pid, nullptr, 0);
            break;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    pid = -1;
}

EmbeddedFarm::~EmbeddedFarm() {
    stop(worker_);
    stop(master_);
    std::error_code ec;
    fs::remove_all(dir_, ec);
}

}  // namespace pf::client
