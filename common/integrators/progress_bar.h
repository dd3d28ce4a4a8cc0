// The embedded renderer's progress bar on stderr (off with `pathfarm render -q`).
#pragma once
#include <cstdio>

#include "core/math.h"

namespace pf {

class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : enabled_(enabled) {}
    void update(double fraction, const char *label) {
        if (!enabled_) return;
        const int width = 40, filled = static_cast<int>(clamp(fraction, 0.0, 1.0) * width);
        std::fprintf(stderr, "\r[%.*s%*s] %5.1f%% %s", filled, "########################################",
                     width - filled, "", 100.0 * clamp(fraction, 0.0, 1.0), label);
        std::fflush(stderr);
    }
    ~ProgressBar() {
        if (enabled_) std::fprintf(stderr, "\n");
    }
    ProgressBar(const ProgressBar &) = delete;
    ProgressBar &operator=(const ProgressBar &) = delete;

private:
    bool enabled_;
};

}  // namespace pf
