#include "batch_governor.h"

#include <algorithm>
#include <ctime>

namespace pf::master {

namespace {
// Halving doubles the share, so a band wider than a factor of two keeps the batch from swinging back.
constexpr double kShrinkBelow = 0.2;

double threadCpuSeconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}
}  // namespace

BatchGovernor::BatchGovernor(double busy, std::chrono::milliseconds window, int most)
    : busy_(busy), window_(window), most_(std::max(1, most)), windowStart_(Clock::now()) {}

void BatchGovernor::record(double cpuSeconds, Clock::time_point now) {
    const std::lock_guard<std::mutex> lock(mu_);
    advance(now);
    windowCpu_ += cpuSeconds;
}

int BatchGovernor::batch(Clock::time_point now) {
    const std::lock_guard<std::mutex> lock(mu_);
    advance(now);
    return batch_;
}

void BatchGovernor::advance(Clock::time_point now) {
    if (now - windowStart_ < window_) return;
    const double share = windowCpu_ / std::chrono::duration<double>(now - windowStart_).count();
    if (share > busy_)
        batch_ = std::min(most_, 2 * batch_);
    else if (share < kShrinkBelow * busy_)
        batch_ = std::max(1, batch_ / 2);
    windowStart_ = now;
    windowCpu_ = 0;
}

BatchGovernor::Meter::Meter(BatchGovernor &g) : g_(g), start_(threadCpuSeconds()) {}

BatchGovernor::Meter::~Meter() { g_.record(threadCpuSeconds() - start_); }

}  // namespace pf::master
