// How many image tasks the master lets a worker lease at once when the worker leaves the choice to it
// (`pathfarm-worker --batch auto`, the default). A batched result costs the master one decode, one file and
// one merge for all its tasks, but its sum rounds differently from the task-by-task merge, so the farm's image
// equals the embedded render only to a few float ulps. The governor therefore batches only when merging
// results keeps the master busy: it measures the CPU time the master spends taking results, and each window
// doubles the batch while that share of one core is above `busy` and halves it while it is below a fifth of
// that. A small farm, where the master idles, keeps batches of one and its images bit for bit; a farm of
// hundreds of workers on small tasks grows its batches until one master core keeps up (issue 17).
#pragma once
#include <chrono>
#include <mutex>

namespace pf::master {

class BatchGovernor {
public:
    using Clock = std::chrono::steady_clock;
    // busy: the share of one core spent taking results above which batches grow; window: how often the
    // batch size may change; most: the largest batch.
    BatchGovernor(double busy, std::chrono::milliseconds window, int most);

    // Counts `cpuSeconds` spent taking one result.
    void record(double cpuSeconds, Clock::time_point now = Clock::now());
    // The batch a worker that leaves the choice to the master gets now.
    int batch(Clock::time_point now = Clock::now());

    // Records the CPU time of the calling thread from construction to destruction (one result taken).
    class Meter {
    public:
        explicit Meter(BatchGovernor &g);
        ~Meter();
        Meter(const Meter &) = delete;
        Meter &operator=(const Meter &) = delete;

    private:
        BatchGovernor &g_;
        double start_;
    };

private:
    // Under mu_: closes the windows that ended by `now`.
    void advance(Clock::time_point now);

    const double busy_;
    const std::chrono::milliseconds window_;
    const int most_;
    std::mutex mu_;
    Clock::time_point windowStart_;
    double windowCpu_ = 0;
    int batch_ = 1;
};

}  // namespace pf::master
