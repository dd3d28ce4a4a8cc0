#include "chain_batch.h"

#include <stdexcept>

#include "render/normalizer.h"

namespace pf::worker {

ChainBatch::ChainBatch(std::vector<int64_t> attempts, size_t maxWaiting)
    : attempts_(std::move(attempts)), ended_(attempts_.size()), maxWaiting_(maxWaiting) {}

std::vector<ChainBatch::Run> ChainBatch::finish(size_t slot, std::optional<ChainResult> result, double loadSeconds) {
    const std::lock_guard<std::mutex> lock(mu_);
    const bool setAside = setAside_.erase(slot) > 0;
    if (slot >= ended_.size() || ended_[slot] || (slot < next_ && !setAside))
        throw std::logic_error("ChainBatch::finish: task " + std::to_string(slot) + " ended twice or is not in it");
    std::vector<Run> done;
    if (setAside) {
        ended_[slot] = Ended{};
        if (result) done.push_back(Run{{attempts_[slot]}, std::move(*result), loadSeconds});
        return done;
    }
    ended_[slot] = Ended{std::move(result), loadSeconds};
    addInTurn(done);
    // The task in turn has not ended and too many results wait for it: it is set aside, and the run before it
    // leaves now.
    while (next_ < ended_.size() && waiting() > maxWaiting_) {
        if (run_) done.push_back(std::move(*run_));
        run_.reset();
        setAside_.insert(next_++);
        addInTurn(done);
    }
    if (next_ == ended_.size() && run_) {
        done.push_back(std::move(*run_));
        run_.reset();
    }
    return done;
}

void ChainBatch::addInTurn(std::vector<Run> &done) {
    // Added in task order, whatever order the threads finish in, so that a batch's sum has the same bits
    // wherever and whenever it is rendered (unless a task was set aside).
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
        e.result.reset();  // its film is in the run now
    }
}

size_t ChainBatch::waiting() const {
    size_t n = 0;
    for (size_t i = next_; i < ended_.size(); ++i) n += ended_[i] && ended_[i]->result ? 1 : 0;
    return n;
}

}  // namespace pf::worker
