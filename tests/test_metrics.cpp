// Error metrics (common/image/metrics.h) against values computed by hand on tiny images, the trim on a
// crafted outlier, errors for images that cannot be compared; and `pathfarm diff` as a user runs it.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "image/bitmap.h"
#include "image/metrics.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

// A grey image (R = G = B) of the given width from row-major values.
Bitmap grey(int w, const std::vector<float> &values) {
    Bitmap b(w, static_cast<int>(values.size()) / w);
    for (size_t i = 0; i < values.size(); ++i) b.rgb[3 * i] = b.rgb[3 * i + 1] = b.rgb[3 * i + 2] = values[i];
    return b;
}

// 2x2 grey images: reference b = (1, 2, 0, 4), image a = (1.5, 2, 0.1, 3), so a - b = (0.5, 0, 0.1, -1).
const Bitmap kRef = grey(2, {1, 2, 0, 4});
const Bitmap kImg = grey(2, {1.5f, 2, 0.1f, 3});

TEST(Metrics, TwoByTwoByHand) {
    const ErrorMetrics m = computeMetrics(kImg, kRef);
    EXPECT_EQ(m.pixels, 4);
    EXPECT_EQ(m.trimmedPixels, 0);
    EXPECT_DOUBLE_EQ(m.options.epsilon, 0.01);
    // The float image holds 0.1f, not 0.1: tolerances of float precision.
    EXPECT_NEAR(m.mse, (0.25 + 0 + 0.01 + 1) / 4, 1e-8);
    EXPECT_NEAR(m.rmse, std::sqrt(0.315), 1e-8);
    EXPECT_NEAR(m.relMse, (0.25 / 1.01 + 0 + 0.01 / 0.01 + 1 / 16.01) / 4, 1e-6);
    EXPECT_NEAR(m.mape, (0.5 / 1.01 + 0 + 0.1 / 0.01 + 1 / 4.01) / 4, 1e-6);
    EXPECT_NEAR(m.smape, (0.5 / 2.51 + 0 + 0.1 / 0.11 + 1 / 7.01) / 4, 1e-6);
    EXPECT_DOUBLE_EQ(m.get(Metric::RelMSE), m.relMse);
    EXPECT_DOUBLE_EQ(m.get(Metric::SMAPE), m.smape);
}

TEST(Metrics, EpsilonIsTheOneGiven) {
    const ErrorMetrics m = computeMetrics(kImg, kRef, {0.5, 0.0});
    EXPECT_NEAR(m.relMse, (0.25 / 1.5 + 0 + 0.01 / 0.5 + 1 / 16.5) / 4, 1e-6);
    EXPECT_NEAR(m.mape, (0.5 / 1.5 + 0 + 0.1 / 0.5 + 1 / 4.5) / 4, 1e-6);
    EXPECT_NE(metricDefinition(Metric::RelMSE, 0.5).find("(b^2 + 0.5)"), std::string::npos);
    EXPECT_NE(metricDefinition(Metric::RelMSE, 0.01).find("(b^2 + 0.01)"), std::string::npos);
}

TEST(Metrics, ChannelsAreAveragedPerPixel) {
    // 3x1: one pixel differs by (0, 1, 2) in R, G, B; the others are exact.
    Bitmap ref(3, 1), img(3, 1);
    for (float &v : ref.rgb) v = 1;
    img = ref;
    img.rgb[4] = 2;
    img.rgb[5] = 3;
    const ErrorMetrics m = computeMetrics(img, ref);
    EXPECT_DOUBLE_EQ(m.mse, (0 + 1 + 4) / 3.0 / 3.0);
    EXPECT_NEAR(m.relMse, (1 / 1.01 + 4 / 1.01) / 3.0 / 3.0, 1e-12);
    EXPECT_NEAR(m.smape, (1 / 3.01 + 2 / 4.01) / 3.0 / 3.0, 1e-12);
    EXPECT_DOUBLE_EQ(computeMetrics(ref, ref).relMse, 0.0);
}

TEST(Metrics, TrimDiscardsTheCraftedOutliers) {
    // 1000 pixels off by 0.5 each (exact in float), two of them fireflies.
    std::vector<float> refValues(1000, 1.0f), imgValues(1000, 1.5f);
    imgValues[17] = 101;
    imgValues[503] = 51;
    const Bitmap ref = grey(40, refValues), img = grey(40, imgValues);
    const ErrorMetrics all = computeMetrics(img, ref);
    EXPECT_DOUBLE_EQ(all.mse, (998 * 0.25 + 100.0 * 100 + 50.0 * 50) / 1000);
    // 0.1% of 1000 pixels: the worst one goes.
    const ErrorMetrics trim1 = computeMetrics(img, ref, {0.01, 0.001});
    EXPECT_EQ(trim1.trimmedPixels, 1);
    EXPECT_DOUBLE_EQ(trim1.mse, (998 * 0.25 + 50.0 * 50) / 999);
    EXPECT_NEAR(trim1.relMse, (998 * 0.25 + 2500.0) / 1.01 / 999, 1e-9);
    // floor(0.0025 * 1000) = 2: both go and the rest is exact.
    const ErrorMetrics trim2 = computeMetrics(img, ref, {0.01, 0.0025});
    EXPECT_EQ(trim2.trimmedPixels, 2);
    EXPECT_DOUBLE_EQ(trim2.mse, 0.25);
    EXPECT_DOUBLE_EQ(trim2.rmse, 0.5);
    EXPECT_NEAR(trim2.mape, 0.5 / 1.01, 1e-12);
    EXPECT_NEAR(trim2.smape, 0.5 / 2.51, 1e-12);
}

TEST(Metrics, ImagesThatCannotBeComparedAreNamed) {
    const auto message = [](const Bitmap &a, const Bitmap &b, MetricOptions o = {}) -> std::string {
        try {
            computeMetrics(a, b, o);
        } catch (const MetricError &e) {
            return e.what();
        }
        return "no error";
    };
    EXPECT_NE(message(kImg, grey(3, {1, 1, 1})).find("2x2 but the reference is 3x1"), std::string::npos);
    Bitmap nan = kImg;
    nan.rgb[4] = std::numeric_limits<float>::quiet_NaN();  // pixel (1, 0), channel G
    const std::string m = message(nan, kRef);
    EXPECT_NE(m.find("the image has a non-finite value"), std::string::npos) << m;
    EXPECT_NE(m.find("pixel (1, 0) channel G"), std::string::npos) << m;
    Bitmap inf = kRef;
    inf.rgb[11] = std::numeric_limits<float>::infinity();  // pixel (1, 1), channel B
    EXPECT_NE(message(kImg, inf).find("the reference has a non-finite value (inf) at pixel (1, 1) channel B"),
              std::string::npos)
        << message(kImg, inf);
    EXPECT_NE(message(Bitmap(), kRef).find("the image is empty"), std::string::npos);
    EXPECT_NE(message(kImg, kRef, {0.0, 0.0}).find("epsilon"), std::string::npos);
    EXPECT_NE(message(kImg, kRef, {0.01, 0.9}).find("trim fraction"), std::string::npos);
    EXPECT_NE(message(kImg, kRef, {0.01, std::nan("")}).find("trim fraction"), std::string::npos);
}

TEST(Metrics, EfficiencyIsInverseErrorTimesTime) {
    EXPECT_DOUBLE_EQ(efficiency(0.5, 4), 0.5);
    EXPECT_TRUE(std::isinf(efficiency(0, 2)));
    EXPECT_THROW(efficiency(0.1, 0), std::invalid_argument);
    EXPECT_THROW(efficiency(-1, 1), std::invalid_argument);
}

TEST(Metrics, ErrorMapsHoldThePerPixelErrors) {
    const ErrorMap rel = errorMap(kImg, kRef, Metric::RelMSE);
    ASSERT_EQ(rel.values.size(), 4u);
    EXPECT_NEAR(rel.values[0], 0.25 / 1.01, 1e-7);
    EXPECT_EQ(rel.values[1], 0.0);
    EXPECT_NEAR(rel.values[3], 1 / 16.01, 1e-7);
    const ErrorMap rmse = errorMap(kImg, kRef, Metric::RMSE);
    EXPECT_NEAR(rmse.values[3], 1.0, 1e-7);
    EXPECT_NEAR(rmse.values[0], 0.5, 1e-7);
    EXPECT_NEAR(rel.values[2], 1.0, 1e-6);  // 0.1^2 / (0 + 0.01)
    // Nearest-rank quantiles of the sorted values (0, 0.0625, 0.2475, 1): the ceil(4q)-th.
    EXPECT_EQ(quantile(rel, 0.0), 0.0);
    EXPECT_EQ(quantile(rel, 0.25), 0.0);
    EXPECT_NEAR(quantile(rel, 0.5), 1 / 16.01, 1e-7);
    EXPECT_NEAR(quantile(rel, 0.51), 0.25 / 1.01, 1e-7);
    EXPECT_NEAR(quantile(rel, 1.0), 1.0, 1e-6);
    EXPECT_THROW(errorMap(kImg, grey(1, {1}), Metric::MSE), MetricError);
}

TEST(Metrics, FalseColourRunsFromBlackToPaleYellowAndIsMonotonic) {
    ErrorMap ramp{11, 1, {}};
    for (int i = 0; i <= 10; ++i) ramp.values.push_back(i * 0.1);
    ramp.values.back() = 7.0;  // above the maximum: clamped to the brightest colour
    const Bitmap c = falseColour(ramp, 1.0);
    double previous = -1;
    for (int x = 0; x < 11; ++x) {
        const Spectrum s = c.get(x, 0);
        const double luminance = 0.2126 * s.r + 0.7152 * s.g + 0.0722 * s.b;
        EXPECT_GT(luminance, previous) << x;
        previous = luminance;
    }
    EXPECT_LT(c.get(0, 0).r + c.get(0, 0).g + c.get(0, 0).b, 0.01);
    const Spectrum top = c.get(10, 0);
    EXPECT_GT(top.r, 0.9);
    EXPECT_GT(top.g, 0.9);
    EXPECT_LT(top.b, 0.5);
}

// `pathfarm diff` as a user runs it.
class Diff : public ::testing::Test {
protected:
    void SetUp() override {
        cli = cliPath();
        ASSERT_FALSE(cli.empty()) << "PATHFARM_CLI is not set (run through ctest)";
        dir = tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
        Bitmap img = kImg;
        img.metadata["pathfarm.renderSeconds"] = "4";
        writeEXR(dir + "/a.exr", img);
        writeEXR(dir + "/b.exr", kRef);
    }
    ProcessResult diff(const std::string &args) { return runCommand(cli + " diff " + args); }
    std::string cli, dir;
};

TEST_F(Diff, PrintsEveryMetricWithEpsilonAndTrim) {
    const ProcessResult r = diff(dir + "/a.exr " + dir + "/b.exr");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const char *s : {"mse", "rmse", "relmse", "mape", "smape", "efficiency", "epsilon 0.01", "trim: none",
                          "(b^2 + 0.01)", "0.315 "})
        EXPECT_NE(r.output.find(s), std::string::npos) << s << "\n" << r.output;
}

TEST_F(Diff, JsonHoldsTheLibraryValues) {
    const ProcessResult r = diff(dir + "/a.exr " + dir + "/b.exr --json --trim 0.25 --epsilon 0.5");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const nlohmann::json j = nlohmann::json::parse(r.output);
    const ErrorMetrics m = computeMetrics(kImg, kRef, {0.5, 0.25});
    EXPECT_EQ(j["trimmedPixels"], 1);
    EXPECT_EQ(j["epsilon"], 0.5);
    EXPECT_EQ(j["trimFraction"], 0.25);
    for (const Metric k : allMetrics()) EXPECT_DOUBLE_EQ(j[metricName(k)].get<double>(), m.get(k)) << metricName(k);
    EXPECT_DOUBLE_EQ(j["efficiency"].get<double>(), 1 / (m.relMse * 4));
    EXPECT_EQ(j["width"], 2);
}

TEST_F(Diff, BadInputNamesTheFileAndExitsWithTwo) {
    writeFile(dir, "not.exr", "this is text, not an image\n");
    writeEXR(dir + "/wide.exr", grey(3, {1, 1, 1}));
    Bitmap nan = kRef;
    nan.rgb[0] = std::numeric_limits<float>::quiet_NaN();
    writeEXR(dir + "/nan.exr", nan);
    struct Case {
        std::string args, expected;
    };
    const std::vector<Case> cases = {
        {dir + "/missing.exr " + dir + "/b.exr", dir + "/missing.exr"},
        {dir + "/a.exr " + dir + "/not.exr", dir + "/not.exr"},
        {dir + "/a.exr " + dir + "/wide.exr", "the image is 2x2 but the reference is 3x1"},
        {dir + "/nan.exr " + dir + "/b.exr", "the image has a non-finite value (nan) at pixel (0, 0)"},
        {dir + "/a.exr " + dir + "/b.exr --trim 0.9", "--trim"},
        {dir + "/a.exr", "reference"},
    };
    for (const Case &c : cases) {
        const ProcessResult r = diff(c.args);
        EXPECT_EQ(r.exitCode, 2) << c.args << "\n" << r.output;
        EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    }
}

}  // namespace
}  // namespace pf::test
