// Running the real `pathfarm` binary from tests.
#pragma once
#include <string>

namespace pf::test {

struct ProcessResult {
    int exitCode = -1;
    std::string output;  // stdout and stderr together
};
// Runs a shell command line, capturing its output.
ProcessResult runCommand(const std::string &commandLine);
// Path of the pathfarm CLI (env PATHFARM_CLI, set by CTest), or "" if unknown.
std::string cliPath();

}  // namespace pf::test
