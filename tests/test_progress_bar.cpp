// The embedded renderer's progress bar (integrators/progress_bar.h): a timed render of a small film updates it
// hundreds of times a second, so it redraws at most every 0.1 s, and its last state is drawn all the same.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "integrators/progress_bar.h"

namespace pf::test {
namespace {

TEST(ProgressBar, ThrottlesRedrawsAndDrawsTheLastState) {
    testing::internal::CaptureStderr();
    {
        ProgressBar bar(true);
        for (int i = 0; i < 1000; ++i) bar.update(i / 2000.0, ("pass " + std::to_string(i)).c_str());
    }
    const std::string out = testing::internal::GetCapturedStderr();
    // The first update draws; a thousand more within well under a second draw a few times at most, and the
    // bar's end draws the last one, then a newline.
    const auto redraws = std::count(out.begin(), out.end(), '\r');
    EXPECT_GE(redraws, 2);
    EXPECT_LE(redraws, 12);
    EXPECT_NE(out.find("pass 0"), std::string::npos);
    EXPECT_NE(out.find("pass 999\n"), std::string::npos) << out;
}

TEST(ProgressBar, ACompleteBarIsDrawnAtOnceAndADisabledOneNever) {
    testing::internal::CaptureStderr();
    {
        ProgressBar bar(true);
        bar.update(0.5, "half");
        bar.update(1.0, "done");  // within 0.1 s of the first, yet drawn: the render is complete
        const std::string now = testing::internal::GetCapturedStderr();
        EXPECT_NE(now.find("100.0% done"), std::string::npos) << now;
        testing::internal::CaptureStderr();
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "\n");

    testing::internal::CaptureStderr();
    {
        ProgressBar bar(false);
        bar.update(0.5, "half");
        bar.update(1.0, "done");
    }
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace pf::test
