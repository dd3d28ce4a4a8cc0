// Input that Mitsuba 0.6 accepts with a warning: parameters that no plugin uses ("Unqueried attribute",
// SceneHandler::endElement). pathfarm renders such scenes with one warning per leftover naming file and
// line; under --strict each is the error it used to be (exit 2). tests/warning_scenes/leftovers.xml has
// one leftover in each of five plugins: film, sensor, BSDF, shape and integrator.
#include <gtest/gtest.h>

#include <filesystem>

#include "farm/job_setup.h"
#include "scene/scene.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf {
namespace {

namespace fs = std::filesystem;

const std::string kLeftovers = std::string(PATHFARM_SOURCE_DIR) + "/tests/warning_scenes/leftovers.xml";

// In the order the loader builds the plugins (a nested object before its parent, as Mitsuba does), then
// the integrator's, which is built after the scene.
const std::vector<std::string> kSceneWarnings = {
    "leftovers.xml:16: hdrfilm: unused parameter 'label'",
    "leftovers.xml:9: perspective: unused parameter 'focusDistance'",
    "leftovers.xml:23: diffuse: unused parameter 'specularReflectance'",
    "leftovers.xml:21: sphere: unused parameter 'radiuss'",
};
const std::string kIntegratorWarning = "leftovers.xml:5: path: unused parameter 'adaptive'";

bool endsWith(const std::string &s, const std::string &tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

TEST(UnusedParameters, LoaderWarnsOncePerLeftoverWithFileAndLine) {
    const auto scene = loadScene(kLeftovers);
    ASSERT_EQ(scene->warnings().size(), kSceneWarnings.size());
    for (size_t i = 0; i < kSceneWarnings.size(); ++i)
        EXPECT_TRUE(endsWith(scene->warnings()[i].str(), kSceneWarnings[i])) << scene->warnings()[i].str();
    std::vector<SceneWarning> warnings;
    const auto integrator = makeIntegrator(*scene, "", {}, false, &warnings);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_TRUE(endsWith(warnings[0].str(), kIntegratorWarning)) << warnings[0].str();
    // The parameters that were used still are: the sphere keeps its default radius, the path its maxDepth.
    EXPECT_EQ(scene->shapes().size(), 1u);
}

TEST(UnusedParameters, StrictLoadRefusesTheFirstLeftover) {
    try {
        loadScene(kLeftovers, {}, true);
        FAIL() << "strict load accepted leftovers";
    } catch (const SceneError &e) {
        EXPECT_TRUE(endsWith(e.what(), "leftovers.xml:16: hdrfilm: unknown parameter 'label'")) << e.what();
    }
    // The integrator is checked apart from the scene (pathfarm picks it after loading).
    const auto scene = loadScene(kLeftovers);
    EXPECT_THROW(makeIntegrator(*scene, "", {}, true), SceneError);
}

TEST(UnusedParameters, CommandLineParametersAreCheckedLikeTheFiles) {
    const auto scene = loadScene(kLeftovers);
    std::vector<SceneWarning> warnings;
    makeIntegrator(*scene, "", {{"adaptive", "false"}, {"maxDeph", "4"}}, false, &warnings);
    ASSERT_EQ(warnings.size(), 2u);
    EXPECT_EQ(warnings[0].str(), "command line (-P adaptive=false): path: unused parameter 'adaptive'");
    EXPECT_EQ(warnings[1].str(), "command line (-P maxDeph=4): path: unused parameter 'maxDeph'");
    EXPECT_THROW(makeIntegrator(*scene, "", {{"maxDeph", "4"}}, true), SceneError);
}

TEST(UnusedParameters, WrongTypesStayErrorsWithoutStrict) {
    // An unused parameter is harmless; a used one that cannot be read is not (Mitsuba refuses it too).
    const std::string dir = test::tempDir("unused_wrong_type");
    const std::string xml = test::writeFile(dir, "scene.xml", R"(<scene version="0.6.0">
	<sensor type="perspective">
		<string name="fov" value="wide"/>
		<film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
	</sensor>
</scene>
)");
    EXPECT_THROW(loadScene(xml), SceneError);
}

TEST(UnusedParameters, CliRendersWithOneWarningEachAndStrictExitsWith2) {
    const std::string cli = test::cliPath();
    if (cli.empty()) GTEST_SKIP() << "PATHFARM_CLI is not set (run the tests through ctest to check the CLI)";
    const std::string dir = test::tempDir("unused_cli");
    const std::string out = dir + "/out.exr";
    const auto r = test::runCommand(cli + " render '" + kLeftovers + "' --spp 1 -q --threads 1 -o '" + out + "'");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(fs::exists(out));
    std::vector<std::string> expected = kSceneWarnings;
    expected.push_back(kIntegratorWarning);
    size_t at = 0;
    for (const std::string &w : expected) {
        const size_t found = r.output.find(w);
        EXPECT_NE(found, std::string::npos) << w << "\n" << r.output;
        // One warning each, in the order above.
        EXPECT_EQ(r.output.find(w, found + 1), std::string::npos) << w;
        EXPECT_GE(found, at) << w;
        if (found != std::string::npos) at = found;
    }
    size_t count = 0;
    for (size_t p = 0; (p = r.output.find("warning: ", p)) != std::string::npos; ++p) ++count;
    EXPECT_EQ(count, expected.size()) << r.output;

    const std::string strictOut = dir + "/strict.exr";
    const auto s =
        test::runCommand(cli + " render '" + kLeftovers + "' --strict --spp 1 -q --threads 1 -o '" + strictOut + "'");
    EXPECT_EQ(s.exitCode, kExitBadInput) << s.output;
    EXPECT_NE(s.output.find("error: "), std::string::npos) << s.output;
    EXPECT_NE(s.output.find("leftovers.xml:16: hdrfilm: unknown parameter 'label'"), std::string::npos) << s.output;
    EXPECT_FALSE(fs::exists(strictOut));
}

}  // namespace
}  // namespace pf
