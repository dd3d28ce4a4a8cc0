#include "mcmc/primary_sample.h"

#include <cmath>

namespace pf {

double SmallStep::operator()(double u, PCG32 &rng) const {
    const double offset = high_ * std::exp(-logRatio_ * rng.nextDouble());
    double v = rng.nextDouble() < 0.5 ? u + offset : u - offset;
    // Wrap onto the circle; a tiny negative v rounds to 1 when shifted, and then wraps to 0.
    if (v < 0) v += 1;
    if (v >= 1) v -= 1;
    return v;
}

void PrimarySample::start(const std::vector<double> &prefix, Sampler &source) {
    u_.clear();
    for (double v : prefix) u_.push_back({v, 0});
    backup_.clear();
    accepted_ = lastLarge_ = 0;
    next_ = 0;
    proposing_ = false;
    source_ = &source;
}

void PrimarySample::propose(bool largeStep, PCG32 &rng) {
    rng_ = &rng;
    source_ = nullptr;
    large_ = largeStep;
    proposing_ = true;
    next_ = 0;
    backup_.clear();
}

void PrimarySample::accept() {
    ++accepted_;
    if (large_) lastLarge_ = accepted_;
    proposing_ = false;
    backup_.clear();
}

void PrimarySample::reject() {
    for (const auto &[index, old] : backup_) u_[index] = old;
    proposing_ = false;
    backup_.clear();
}

double PrimarySample::fresh() { return source_ ? source_->next1D() : rng_->nextDouble(); }

double PrimarySample::next1D() {
    if (next_ == u_.size()) u_.push_back({fresh(), accepted_});
    const size_t index = next_++;
    Coordinate &c = u_[index];
    if (!proposing_) return c.value;
    // Catch up with the accepted transitions this coordinate missed.
    if (c.time < lastLarge_) c = {fresh(), lastLarge_};
    for (; c.time < accepted_; ++c.time) c.value = smallStep_(c.value, *rng_);
    backup_.emplace_back(index, c);
    c = {large_ ? fresh() : smallStep_(c.value, *rng_), accepted_ + 1};
    return c.value;
}

std::vector<PrimarySample::Change> PrimarySample::changes() const {
    std::vector<Change> out;
    for (const auto &[index, old] : backup_) out.push_back({index, old.value, u_[index].value});
    return out;
}

}  // namespace pf
