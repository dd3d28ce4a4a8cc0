#include "farm/netns.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <exception>
#include <filesystem>
#include <regex>
#include <stdexcept>
#include <thread>

#include "support/process.h"

namespace pf::test::farm {

namespace fs = std::filesystem;

namespace {

constexpr const char *kNetnsDir = "/run/netns";  // where `ip netns add` pins namespaces by name
constexpr const char *kSubnet = "10.87.0.";

// The iproute2 binary, or "" when it is not installed.
std::string ipBinary() {
    for (const char *p : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"})
        if (access(p, X_OK) == 0) return p;
    return "";
}

// Runs `ip ARGS`; "" on success, else the command and what it printed.
std::string tryIp(const std::string &args) {
    const std::string ip = ipBinary();
    if (ip.empty()) return "iproute2 ('ip') is not installed";
    const ProcessResult r = runCommand(ip + " " + args);
    return r.exitCode == 0 ? "" : "'ip " + args + "' failed: " + r.output;
}

void ip(const std::string &args) {
    const std::string error = tryIp(args);
    if (!error.empty()) throw std::runtime_error(error);
}

std::string quoted(const std::string &s) {
    std::string q = "'";
    for (const char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

// Namespaces of earlier test processes (pfnet-<pid>-...) whose process is gone: a test that was killed
// could not run its destructor.
void removeStale() {
    std::error_code ec;
    const std::regex ours("pfnet-(\\d+)-.*");
    for (const auto &entry : fs::directory_iterator(kNetnsDir, ec)) {
        const std::string name = entry.path().filename().string();
        std::smatch m;
        if (!std::regex_match(name, m, ours)) continue;
        const pid_t pid = static_cast<pid_t>(std::stol(m[1]));
        if (pid != getpid() && kill(pid, 0) != 0 && errno == ESRCH) tryIp("netns delete " + name);
    }
}

}  // namespace

std::string NetnsLan::unavailableReason() {
    if (geteuid() != 0) return "needs root (CAP_NET_ADMIN) to create network namespaces";
    if (ipBinary().empty()) return "iproute2 ('ip') is not installed";
    const std::string probe = "pfnet-" + std::to_string(getpid()) + "-probe";
    std::string error = tryIp("netns add " + probe);
    if (!error.empty()) return "cannot create a network namespace: " + error;
    error = tryIp("-n " + probe + " link add br0 type bridge");
    if (error.empty()) error = tryIp("-n " + probe + " link add v0 type veth peer name v1");
    tryIp("netns delete " + probe);
    return error.empty() ? "" : "cannot create a bridge and veth pair: " + error;
}

NetnsLan::NetnsLan(const std::string &tag)
    : prefix_("pfnet-" + std::to_string(getpid()) + "-" + tag), switch_(prefix_ + "-switch") {
    removeStale();
    ip("netns add " + switch_);
    switchCreated_ = true;
    ip("-n " + switch_ + " link add br0 type bridge");
    ip("-n " + switch_ + " link set br0 up");
}

NetnsLan::~NetnsLan() {
    // A namespace's interfaces go with it; a veth pair goes when either end does.
    for (const Host &h : hosts_) tryIp("netns delete " + h.netns);
    if (switchCreated_) tryIp("netns delete " + switch_);
}

NetnsLan::Host NetnsLan::addHost(const std::string &name) {
    const std::string index = std::to_string(hosts_.size() + 1);
    Host h{name, prefix_ + "-" + name, kSubnet + index};
    ip("netns add " + h.netns);
    hosts_.push_back(h);  // from now on the destructor removes it
    ip("-n " + h.netns + " link set lo up");
    // The switch's end of the cable is the bridge port v<index>; the host's end is its eth0.
    const std::string port = "v" + index;
    ip("-n " + switch_ + " link add " + port + " type veth peer name eth0 netns " + h.netns);
    ip("-n " + switch_ + " link set " + port + " master br0");
    ip("-n " + switch_ + " link set " + port + " up");
    ip("-n " + h.netns + " addr add " + h.address + "/24 dev eth0");
    ip("-n " + h.netns + " link set eth0 up");
    return h;
}

std::vector<std::string> NetnsLan::exec(const Host &host, const std::vector<std::string> &argv) const {
    std::vector<std::string> full = {ipBinary(), "netns", "exec", host.netns};
    full.insert(full.end(), argv.begin(), argv.end());
    return full;
}

std::string NetnsLan::shell(const Host &host, const std::string &commandLine) const {
    return ipBinary() + " netns exec " + host.netns + " sh -c " + quoted(commandLine);
}

void NetnsLan::runIn(const Host &host, const std::function<void()> &fn) const {
    // setns(CLONE_NEWNET) moves only the calling thread, so a fresh thread joins the host and the
    // test's other threads stay where they are.
    std::exception_ptr failure;
    std::thread([&] {
        try {
            const std::string path = std::string(kNetnsDir) + "/" + host.netns;
            const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
            if (fd < 0) throw std::runtime_error("cannot open " + path);
            const int rc = setns(fd, CLONE_NEWNET);
            close(fd);
            if (rc != 0) throw std::runtime_error("cannot join network namespace " + host.netns);
            fn();
        } catch (...) {
            failure = std::current_exception();
        }
    }).join();
    if (failure) std::rethrow_exception(failure);
}

void NetnsLan::setLink(const Host &host, bool up) const {
    ip("-n " + host.netns + " link set eth0 " + (up ? "up" : "down"));
}

}  // namespace pf::test::farm
