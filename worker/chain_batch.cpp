#include "chain_batch.h"

#include <stdexcept>

#include "render/normalizer.h"

namespace pf::worker {

ChainBatch::ChainBatch(std::vector<int64_t> attempts) : attempts_(std::move(attempts)), ended_(attempts_.size()) {}

std::vector<ChainBatch::Run> ChainBatch::finish(size_t slot, std::optional<ChainResult> result, double loadSeconds) {
    const std::lock_guard<std::mutex> lock(mu_);
    if (slot >= ended_.size() || ended_[slot] || slot < next_)
        throw std::logic_error("ChainBatch::finish: task " + std::to_string(slot) + " ended twice or is not in it");
    ended_[slot] = Ended{std::move(result), loadSeconds};
    std::vector<Run> done;
    // Added in task order, whatever order the threads finish in, so that a batch's sum has the same bits
    // wherever and whenever it is rendered.
    for (; next_ < ended_.size() && ended_[next_]; ++next_) {
        Ended &e = *ended_[next_];
        if (!e.result) {
            if (run_) done.push_back(std::move(*run_));
            run_.reset();
        } else if (run_) {
            addChainResult(run_->sum, *e.result);
            run_->attempts.push_back(attempts_[next_]);
            run_->loadSeconds += e.loadSeconds;
        } else {
            run_ = Run{{attempts_[next_]}, std::move(*e.result), e.loadSeconds};
        }
        ended_[next_]->result.reset();  // its film is in the run now
    }
    if (next_ == ended_.size() && run_) {
        done.push_back(std::move(*run_));
        run_.reset();
    }
    return done;
}

}  // namespace pf::worker
