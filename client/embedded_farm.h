// A farm on this machine for `pathfarm compare` without --master: a pathfarm-master on a loopback port
// and one pathfarm-worker, started from the binaries beside the running `pathfarm`, with fresh random
// tokens and their data in a temporary directory. The comparison then talks to it exactly as it talks
// to a remote master, so both modes run the same code.
#pragma once
#include <sys/types.h>

#include <string>

#include "farm_client.h"

namespace pf::client {

class EmbeddedFarm {
public:
    // Starts the master and the worker (`threads` render threads, 0 = all cores) and waits until the
    // worker has registered. Throws std::runtime_error with the processes' logs on failure.
    explicit EmbeddedFarm(int threads);
    // Stops both processes (SIGTERM, then SIGKILL after a grace period) and removes the directory.
    ~EmbeddedFarm();
    EmbeddedFarm(const EmbeddedFarm &) = delete;
    EmbeddedFarm &operator=(const EmbeddedFarm &) = delete;

    const FarmConnection &connection() const { return connection_; }

private:
    void stop(pid_t &pid);
    std::string dir_;
    pid_t master_ = -1, worker_ = -1;
    FarmConnection connection_;
};

}  // namespace pf::client
