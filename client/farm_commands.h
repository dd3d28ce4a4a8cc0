// The `pathfarm` commands that talk to a farm master: submit, status, watch, fetch, cancel, workers,
// health. The master is found from --master or PATHFARM_MASTER, the client token from --token-file or
// PATHFARM_TOKEN.
#pragma once
#include <CLI/CLI.hpp>
#include <memory>
#include <string>

namespace pf::client {

// The output a render or a job of `scenePath` is written to by default: dir/scene.xml -> dir.exr,
// other.xml -> other.exr.
std::string defaultOutput(const std::string &scenePath);

// The --reconnect-timeout option of the commands that ride out a master restart, into `seconds`
// (FarmConnection::reconnectSeconds), which it sets to the default.
CLI::Option *addReconnectOption(CLI::App &cmd, int &seconds);

class FarmCommands {
public:
    explicit FarmCommands(CLI::App &app);
    ~FarmCommands();
    // Runs the farm subcommand that was parsed, if any: its exit code, or -1 when none was chosen.
    int run();

private:
    struct Args;
    std::unique_ptr<Args> a_;
};

}  // namespace pf::client
