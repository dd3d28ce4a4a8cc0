// `sms` runs on the farm as image tasks, like `path`: the farm's image equals the embedded render bit for bit.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <regex>
#include <sstream>

#include "farm/harness.h"
#include "image/bitmap.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

class FarmSms : public FarmTest {};

// scenes/pool-caustic at 24 x 24 (in the farm's directory), with `edit` applied to its text.
std::string poolScene(const std::string &dir, const std::function<std::string(std::string)> &edit = {}) {
    std::ifstream in(std::string(PATHFARM_SOURCE_DIR) + "/scenes/pool-caustic/scene.xml");
    std::stringstream xml;
    xml << in.rdbuf();
    const std::string small = std::regex_replace(xml.str(), std::regex(R"(value="256")"), R"(value="24")");
    return writeFile(dir, "pool.xml", edit ? edit(small) : small);
}

TEST_F(FarmSms, ImageTasksMatchTheEmbeddedRender) {
    const std::string scene = poolScene(farm->dir());
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

// A flag that sms cannot honour (a diffuse caster) is refused when the job is set up, as by the embedded
// render, naming the file and line, and the master goes on.
TEST_F(FarmSms, ImpossibleFlagsAreRefusedAtSubmission) {
    const std::string scene = poolScene(farm->dir(), [](std::string xml) {
        const size_t diffuse = xml.find(R"(<bsdf type="diffuse">)");
        return xml.insert(diffuse, R"(<boolean name="causticCaster" value="true"/>)");
    });
    farm->startMaster();
    const auto [code, output] = farm->cli("submit " + scene + " --integrator sms --spp 1");
    EXPECT_NE(code, 0) << output;
    EXPECT_NE(output.find("pool.xml:"), std::string::npos) << output;
    EXPECT_NE(output.find("causticCaster"), std::string::npos) << output;
    EXPECT_TRUE(farm->master().running());
}

}  // namespace
}  // namespace pf::test::farm
