// Several hosts on one machine, without containers: each host is a Linux network namespace joined by a
// veth pair to a bridge that lives in a namespace of its own (the switch), with addresses on a private
// /24. Processes started through exec() see only their host's interfaces, so a master listening on its
// host's address is reached by workers in other hosts through real IP routing, and pulling a host's
// cable (setLink) cuts it off mid-conversation. Needs root with CAP_NET_ADMIN.
//
// Nothing is created in the caller's own namespace: deleting the namespaces removes every interface, so
// the destructor leaves the machine as it was. Namespace names carry the creating process id, so tests
// running side by side never collide, and the namespaces of a test process that died without cleaning
// up are removed by the next one.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace pf::test::farm {

class NetnsLan {
public:
    struct Host {
        std::string name;     // as given to addHost
        std::string netns;    // the namespace (ip netns exec NETNS ...)
        std::string address;  // IPv4 address on the LAN
    };

    // Why a LAN cannot be built on this machine, or "" when it can: tries the whole recipe (namespace,
    // bridge, veth) on a probe namespace, so that a test skips for the true reason.
    static std::string unavailableReason();

    // A switch with no hosts yet on 10.87.0.0/24 (RFC 1918; namespaces isolate it from the machine's
    // own networks). `tag` goes into the namespace names. Throws std::runtime_error naming the command
    // that failed.
    explicit NetnsLan(const std::string &tag);
    ~NetnsLan();
    NetnsLan(const NetnsLan &) = delete;
    NetnsLan &operator=(const NetnsLan &) = delete;

    // A new host with its loopback up and eth0 on the switch, at the next address (.1, .2, ...).
    Host addHost(const std::string &name);
    const std::vector<Host> &hosts() const { return hosts_; }

    // `argv` prefixed so that it runs inside the host (for a process launcher taking an argv).
    std::vector<std::string> exec(const Host &host, const std::vector<std::string> &argv) const;
    // A shell command line that runs `commandLine` inside the host.
    std::string shell(const Host &host, const std::string &commandLine) const;
    // Runs `fn` on a thread that has joined the host's namespace: sockets it opens are the host's.
    void runIn(const Host &host, const std::function<void()> &fn) const;
    // Takes the host's eth0 down or up, as if its cable were pulled or plugged back in.
    void setLink(const Host &host, bool up) const;

private:
    std::string prefix_;  // pf-<tag>-<pid>
    std::string switch_;  // the namespace holding the bridge
    std::vector<Host> hosts_;
    bool switchCreated_ = false;
};

}  // namespace pf::test::farm
