// `sms` runs on the farm as image tasks, like `path`: the farm's image equals the embedded render bit for bit.
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "farm/harness.h"
#include "image/bitmap.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

class FarmSms : public FarmTest {};

TEST_F(FarmSms, ImageTasksMatchTheEmbeddedRender) {
    std::ifstream in(std::string(PATHFARM_SOURCE_DIR) + "/scenes/pool-caustic/scene.xml");
    std::stringstream xml;
    xml << in.rdbuf();
    const std::string scene = writeFile(farm->dir(), "pool.xml",
                                        std::regex_replace(xml.str(), std::regex(R"(value="256")"), R"(value="24")"));
    const std::string spec = "--integrator sms --spp 12 --seed 5";
    const std::string ref = farm->embeddedRender(scene, spec, "reference");
    farm->startMaster(kFastLeases);
    for (int i = 0; i < 2; ++i) farm->startWorker(1);
    const std::string out = farm->dir() + "/farm.exr";
    const auto [code, output] = farm->cli("submit " + scene + " " + spec + " --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    EXPECT_TRUE(sameBits(ref, out));
    EXPECT_EQ(readEXR(out).metadata.at("pathfarm.integrator"), "sms");
}

}  // namespace
}  // namespace pf::test::farm
