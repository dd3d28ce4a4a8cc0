// User-facing errors. Every problem with user input is reported as a SceneError carrying the file and
// line (or the parameter) it concerns; the CLI prints it and exits with code 2.
#pragma once
#include <stdexcept>
#include <string>

namespace pf {

struct SourceLocation {
    std::string file;
    int line = 0;  // 0 = unknown
    std::string str() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

class SceneError : public std::runtime_error {
public:
    SceneError(const SourceLocation &loc, const std::string &msg)
        : std::runtime_error(loc.file.empty() ? msg : loc.str() + ": " + msg), loc_(loc) {}
    explicit SceneError(const std::string &msg) : std::runtime_error(msg) {}
    const SourceLocation &location() const { return loc_; }

private:
    SourceLocation loc_;
};

// Exit code for bad input (issue 3: "exit code 2").
constexpr int kExitBadInput = 2;

}  // namespace pf
