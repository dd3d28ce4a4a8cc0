#include "support/process.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>

namespace pf::test {

ProcessResult runCommand(const std::string &commandLine) {
    ProcessResult r;
    FILE *pipe = popen((commandLine + " 2>&1").c_str(), "r");
    if (!pipe) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
    const int status = pclose(pipe);
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

std::string cliPath() {
    const char *p = std::getenv("PATHFARM_CLI");
    return p ? p : "";
}

}  // namespace pf::test
