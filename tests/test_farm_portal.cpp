// The portal perturbation on the farm: an `mlt` job with portalPerturbation=true on scenes/portal-toy (the
// portal travels in the scene bundle, the parameters with the job like every integrator parameter) gives the
// embedded `pathfarm render` of the same spec and seed bit for bit, and the job record counts the portal
// perturbation's proposals and acceptances with the other mutation types.
#include <gtest/gtest.h>

#include <filesystem>

#include "farm/harness.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

class FarmPortal : public FarmTest {};

TEST_F(FarmPortal, MLTJobWithPortalsMatchesTheEmbeddedRender) {
    const std::string dir = farm->dir() + "/scene";
    std::filesystem::create_directories(dir);
    std::filesystem::copy_file(std::string(PATHFARM_SOURCE_DIR) + "/scenes/portal-toy/scene.xml", dir + "/scene.xml");
    const std::string scene = dir + "/scene.xml";
    farm->startMaster();
    farm->startWorker(2);
    const std::string spec =
        "--integrator mlt --spp 16 --seed 7 -D res=24 -P maxDepth=4 -P luminanceSamples=4096 -P directSamples=2 "
        "-P lensSubpathMutation=false -P causticPerturbation=false -P multiChainPerturbation=false "
        "-P portalPerturbation=true";
    std::string out, ref;
    const v1::Job job = farm->submitMatchingEmbedded(scene, spec, out, ref);
    ASSERT_EQ(job.state(), v1::JOB_DONE);
    bool portal = false;
    for (const v1::MutationCount &m : job.chain().mutation_counts())
        if (m.name() == "portal") {
            portal = true;
            EXPECT_GT(m.proposed(), 100u);
            EXPECT_GT(m.accepted(), 0u);
            EXPECT_NEAR(m.acceptance(), static_cast<double>(m.accepted()) / static_cast<double>(m.proposed()), 1e-9);
        }
    EXPECT_TRUE(portal) << "the job record lists the portal perturbation";
}

}  // namespace
}  // namespace pf::test::farm
