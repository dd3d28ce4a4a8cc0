// A batch of chain tasks on a worker (issue 17): the master leases a run of chain tasks that follow each other
// in a job, the worker's threads run them one per thread as usual, and their results are added up in task
// order and leave as one result naming every attempt, which the master decodes and merges once. A chain task's
// film covers most of a 1024² image (erpt's tasks: 70-87% of its 8² tiles), so a batch's sum is barely larger
// than one task's: the bytes on the wire and the master's decoding per task fall about as 1 / (tasks).
// A task that fails or whose lease is lost ends the run before it; the tasks after it start a new run.
#pragma once
#include <cstdint>
#include <mutex>
#include <optional>
#include <vector>

#include "render/chain.h"

namespace pf::worker {

class ChainBatch {
public:
    // The attempts of the batch's tasks, in task order.
    explicit ChainBatch(std::vector<int64_t> attempts);

    // Results of tasks that follow each other, summed: the first task's attempt, then the others'.
    struct Run {
        std::vector<int64_t> attempts;
        ChainResult sum;
        double loadSeconds = 0;
    };
    // Task `slot` ended, with its result or without one (it failed, or its lease was lost). Returns the runs
    // that are complete now: those ended by a task without a result, and the last one once every task ended.
    std::vector<Run> finish(size_t slot, std::optional<ChainResult> result, double loadSeconds);

private:
    struct Ended {
        std::optional<ChainResult> result;
        double loadSeconds = 0;
    };
    std::mutex mu_;
    std::vector<int64_t> attempts_;
    std::vector<std::optional<Ended>> ended_;  // tasks ended ahead of their turn wait here
    size_t next_ = 0;                          // the first task not yet added to a run
    std::optional<Run> run_;
};

}  // namespace pf::worker
