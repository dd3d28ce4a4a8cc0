// A batch of chain tasks on a worker (issue 17): the master leases a run of chain tasks that follow each other
// in a job (past the direct tasks between them, which it leases apart: Master::batchRow), the worker's threads run
// them one per thread as usual, and their results are added up in task order and leave as one result naming every
// attempt, which the master decodes and merges once. A chain task's film covers most of a 1024² image (erpt's
// tasks: 70-87% of its 8² tiles), so a batch's sum is barely larger than one task's: the bytes on the wire and the
// master's decoding per task fall about as 1 / (tasks).
// A task that fails or whose lease is lost ends the run before it; the tasks after it start a new run.
// Results that end ahead of their turn wait for it, each with a film of most of the image. So that a slow task
// cannot make them pile up (a batch may hold 1024 tasks), a task that holds up more than `maxWaiting` of them is
// set aside: it leaves as a run of its own when it ends, and the runs before and after it go on without it. Which
// tasks are set aside depends on timing, so such a batch's bits do too; every task is still merged once.
#pragma once
#include <cstdint>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <vector>

#include "render/chain.h"

namespace pf::worker {

class ChainBatch {
public:
    // The attempts of the batch's tasks, in task order; at most `maxWaiting` results wait for their turn.
    explicit ChainBatch(std::vector<int64_t> attempts, size_t maxWaiting = std::numeric_limits<size_t>::max());

    // Results of tasks that follow each other, summed: the first task's attempt, then the others'.
    struct Run {
        std::vector<int64_t> attempts;
        ChainResult sum;
        double loadSeconds = 0;
    };
    // Task `slot` ended, with its result or without one (it failed, or its lease was lost). Returns the runs
    // that are complete now: those ended by a task without a result or set aside, a task set aside, and the last
    // run once every task ended.
    std::vector<Run> finish(size_t slot, std::optional<ChainResult> result, double loadSeconds);

private:
    // Adds the tasks that ended in turn to the run, closing runs at tasks without a result.
    void addInTurn(std::vector<Run> &done);
    size_t waiting() const;

    struct Ended {
        std::optional<ChainResult> result;
        double loadSeconds = 0;
    };
    std::mutex mu_;
    std::vector<int64_t> attempts_;
    std::vector<std::optional<Ended>> ended_;  // tasks ended ahead of their turn wait here
    size_t next_ = 0;                          // the first task not yet added to a run or set aside
    size_t maxWaiting_;
    std::set<size_t> setAside_;  // tasks that held up too many results and have not ended yet
    std::optional<Run> run_;
};

}  // namespace pf::worker
