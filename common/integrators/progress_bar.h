// The embedded renderer's progress bar on stderr (off with `pathfarm render -q`).
#pragma once
#include <chrono>
#include <cstdio>
#include <string>

#include "core/math.h"

namespace pf {

// Redrawn at most every 0.1 s: a timed render of a small film runs hundreds of passes a second, and each
// redraw is a write to the terminal. The last state is always drawn, at the latest when the bar goes away.
class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : enabled_(enabled) {}
    void update(double fraction, const char *label) {
        if (!enabled_) return;
        fraction_ = clamp(fraction, 0.0, 1.0);
        label_ = label;
        const auto now = Clock::now();
        if (drawn_ && now - lastDraw_ < kInterval && fraction_ < 1.0) {
            pending_ = true;
            return;
        }
        draw();
        lastDraw_ = now;
    }
    ~ProgressBar() {
        if (!enabled_) return;
        if (pending_) draw();
        std::fprintf(stderr, "\n");
    }
    ProgressBar(const ProgressBar &) = delete;
    ProgressBar &operator=(const ProgressBar &) = delete;

private:
    using Clock = std::chrono::steady_clock;
    static constexpr std::chrono::milliseconds kInterval{100};

    void draw() {
        const int width = 40, filled = static_cast<int>(fraction_ * width);
        std::fprintf(stderr, "\r[%.*s%*s] %5.1f%% %s", filled, "########################################",
                     width - filled, "", 100.0 * fraction_, label_.c_str());
        std::fflush(stderr);
        drawn_ = true;
        pending_ = false;
    }

    bool enabled_;
    bool drawn_ = false, pending_ = false;
    double fraction_ = 0;
    std::string label_;
    Clock::time_point lastDraw_{};
};

}  // namespace pf
