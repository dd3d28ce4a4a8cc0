// `pathfarm diff IMAGE.exr REFERENCE.exr [--trim F] [--epsilon E] [--json]`: every error metric of an
// image against a reference (image/metrics.h), with the epsilon and the trim stated, and the efficiency
// when the image records its render time. Bad input (missing file, not an EXR, different sizes,
// NaN pixels) is an error naming the file, exit code 2.
#pragma once
#include <CLI/CLI.hpp>
#include <memory>

namespace pf::client {

class DiffCommand {
public:
    explicit DiffCommand(CLI::App &app);
    ~DiffCommand();
    // Runs the command if `diff` was parsed: its exit code, else -1.
    int run();

private:
    struct Args;
    std::unique_ptr<Args> a_;
};

}  // namespace pf::client
