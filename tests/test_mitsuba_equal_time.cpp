// scripts/mitsuba-equal-time.sh, the helper that renders a scene with Mitsuba 0.6 for equal-time comparisons
// (issue 17). Mitsuba is not a dependency, so a stand-in executable takes its place: it is called the way the
// script calls Mitsuba (`-q -p THREADS -o OUT SCENE`) and either writes the scene it was given as its image, or
// writes nothing and exits with 0, as Mitsuba 0.6 does when its render job throws.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "support/process.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

std::string script() { return std::string(PATHFARM_SOURCE_DIR) + "/scripts/mitsuba-equal-time.sh"; }
std::string cornellBox() { return std::string(PATHFARM_SOURCE_DIR) + "/scenes/cornell-box/scene.xml"; }

std::string slurp(const std::string &path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

// A stand-in for Mitsuba's wrapper: copies its scene argument (the last) to the -o argument when `writes`.
std::string standIn(const std::string &dir, bool writes) {
    const std::string path = writeFile(dir, writes ? "mitsuba-writes" : "mitsuba-writes-nothing",
                                       writes ? "#!/bin/sh\n"
                                                "while [ $# -gt 1 ]; do [ \"$1\" = -o ] && out=$2; shift; done\n"
                                                "cp \"$1\" \"$out\"\n"
                                              : "#!/bin/sh\necho 'RenderJob: caught exception'\nexit 0\n");
    std::filesystem::permissions(path, std::filesystem::perms::owner_all);
    return path;
}

TEST(MitsubaEqualTime, ARenderThatWritesNoImageIsAnError) {
    const std::string dir = tempDir("MitsubaEqualTimeNoImage");
    const auto r = runCommand("MITSUBA_COUNT=3 bash " + script() + " " + standIn(dir, false) + " " + cornellBox() +
                              " path 10 16 " + dir + "/out.exr 2");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("error: mitsuba wrote no image for " + cornellBox() + " (path)"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("caught exception"), std::string::npos) << "the log is shown: " << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir + "/out.exr"));
}

TEST(MitsubaEqualTime, MarkovChainsGetTheIndependentSamplerAndOthersKeepTheFiles) {
    const std::string dir = tempDir("MitsubaEqualTimeSampler");
    const std::string mitsuba = standIn(dir, true);
    for (const std::string integrator : {"mlt", "pssmlt", "erpt", "path"}) {
        SCOPED_TRACE(integrator);
        const std::string out = dir + "/" + integrator + ".exr";
        const auto r = runCommand("MITSUBA_COUNT=3 bash " + script() + " " + mitsuba + " " + cornellBox() + " " +
                                  integrator + " 10 16 " + out + " 2");
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_NE(r.output.find("mitsuba " + integrator + ": 3 samples per pixel at 16x16"), std::string::npos)
            << r.output;
        const std::string scene = slurp(out);  // the copy Mitsuba was given
        EXPECT_NE(scene.find("<integrator type=\"" + integrator + "\""), std::string::npos);
        EXPECT_NE(scene.find("name=\"sampleCount\" value=\"3\""), std::string::npos);
        EXPECT_NE(scene.find("name=\"width\" value=\"16\""), std::string::npos);
        EXPECT_NE(scene.find("version=\"0.6.0\""), std::string::npos);
        const bool chain = integrator != "path";
        EXPECT_EQ(scene.find("<sampler type=\"independent\"") != std::string::npos, chain) << scene;
        EXPECT_EQ(scene.find("<sampler type=\"sobol\"") != std::string::npos, !chain) << scene;
    }
}

}  // namespace
}  // namespace pf::test
