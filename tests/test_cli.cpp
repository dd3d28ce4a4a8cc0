// The `pathfarm render` command as a user runs it: a real process, real files read back.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>

#include "image/bitmap.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

const char *kScene = R"(<scene version="0.6.0">
  <default name="res" value="24"/>
  <integrator type="path"><integer name="maxDepth" value="4"/></integrator>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="toWorld"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <sampler type="independent"><integer name="sampleCount" value="2"/></sampler>
    <film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film>
  </sensor>
  <emitter type="constant"><spectrum name="radiance" value="1"/></emitter>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
</scene>
)";

class Cli : public ::testing::Test {
protected:
    void SetUp() override {
        cli = cliPath();
        ASSERT_FALSE(cli.empty()) << "PATHFARM_CLI is not set (run through ctest)";
        dir = tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
        scene = writeFile(dir, "scene.xml", kScene);
    }
    std::string cli, dir, scene;
};

TEST_F(Cli, RenderWritesExrWithMetadataAndPng) {
    const auto r = runCommand(cli + " render " + scene + " -q --spp 3 --seed 5 -D res=20 -o " + dir + "/out.exr");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("samples/s"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("rays/s"), std::string::npos) << r.output;
    const Bitmap img = readEXR(dir + "/out.exr");
    EXPECT_EQ(img.width, 20);
    EXPECT_EQ(img.height, 20);
    EXPECT_EQ(img.metadata.at("pathfarm.integrator"), "path");
    EXPECT_EQ(img.metadata.at("pathfarm.spp"), "3");
    EXPECT_EQ(img.metadata.at("pathfarm.seed"), "5");
    EXPECT_TRUE(img.metadata.count("pathfarm.renderSeconds"));
    EXPECT_TRUE(img.metadata.count("pathfarm.sceneLoadSeconds"));
    const Bitmap png = readLDR(dir + "/out.png", false);
    EXPECT_EQ(png.width, 20);
}

TEST_F(Cli, SameBitsWhateverTheThreadCount) {
    ASSERT_EQ(runCommand(cli + " render " + scene + " -q --spp 2 --threads 1 -o " + dir + "/a.exr").exitCode, 0);
    ASSERT_EQ(runCommand(cli + " render " + scene + " -q --spp 2 --threads 2 -o " + dir + "/b.exr").exitCode, 0);
    const Bitmap a = readEXR(dir + "/a.exr"), b = readEXR(dir + "/b.exr");
    ASSERT_EQ(a.rgb.size(), b.rgb.size());
    EXPECT_EQ(0, std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * sizeof(float)));
}

// Whole passes, then a partial one in the time they leave (render/image_task.h): at 256² the tiles are 32², one
// sample per pixel takes about 15 ms here, and where a partial pass ran (three runs of three here: 12%, 19%, 88%
// of the pixels), the summary line and the EXR say how many pixels it covered.
TEST_F(Cli, TimeBudgetIsSpentInWholePassesAndAPartialOne) {
    const auto r = runCommand(cli + " render " + scene + " -q --time 1 -D res=256 -o " + dir + "/t.exr");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const Bitmap img = readEXR(dir + "/t.exr");
    EXPECT_GE(std::stoi(img.metadata.at("pathfarm.spp")), 1);
    const double seconds = std::stod(img.metadata.at("pathfarm.renderSeconds"));
    EXPECT_GT(seconds, 0.5);
    EXPECT_LT(seconds, 3.0);
    const auto partial = img.metadata.find("pathfarm.partialPassPixels");
    if (partial == img.metadata.end()) {
        EXPECT_EQ(r.output.find(" + 1 in "), std::string::npos) << r.output;
        return;
    }
    const int pixels = std::stoi(partial->second);
    EXPECT_GT(pixels, 0);
    EXPECT_LT(pixels, 256 * 256);
    EXPECT_EQ(pixels % (32 * 32), 0) << "whole 32² tiles";
    // The share as printf rounds it (8 tiles are 12.5%, printed as 12).
    char share[64];
    std::snprintf(share, sizeof share, "%d spp + 1 in %.0f%% of pixels", std::stoi(img.metadata.at("pathfarm.spp")),
                  100.0 * pixels / 65536.0);
    EXPECT_NE(r.output.find(share), std::string::npos) << r.output;
}

TEST_F(Cli, BadInputExitsWithCodeTwo) {
    auto r = runCommand(cli + " render " + dir + "/missing.xml -q");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("missing.xml"), std::string::npos) << r.output;
    r = runCommand(cli + " render " + scene + " -q --spp -3");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    r = runCommand(cli + " render " + scene + " -q --integrator nosuch");
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("nosuch"), std::string::npos) << r.output;
    r = runCommand(cli + " render " + scene + " -q -D res");
    EXPECT_EQ(r.exitCode, 2) << r.output;
}

}  // namespace
}  // namespace pf::test
