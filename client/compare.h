// `pathfarm compare SCENE --integrators a,b,... --time S`: the equal-time comparison of rendering
// algorithms on a farm (ARCHITECTURE.md "Equal time"; ALGORITHMS.md §8.3). Every (integrator,
// repetition) is one job with the same wall budget on the same workers, submitted one at a time; the
// running image is fetched at snapshot times for convergence plots; the final images are measured
// against a reference (given, or rendered with BDPT on the farm and cached) and written with
// report.json and index.html to the output directory. Without --master the farm is an embedded one of
// loopback processes (embedded_farm.h), so both modes run the same code.
#pragma once
#include <CLI/CLI.hpp>
#include <memory>

namespace pf::client {

class CompareCommand {
public:
    explicit CompareCommand(CLI::App &app);
    ~CompareCommand();
    // Runs the comparison if `compare` was parsed: its exit code, else -1. Bad options and input throw
    // SceneError (exit code 2).
    int run();

private:
    struct Args;
    std::unique_ptr<Args> a_;
};

}  // namespace pf::client
