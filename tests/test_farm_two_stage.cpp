// Two-stage MLT on the farm (render/two_stage.h): the first stage's image travels with the seeding
// results (sums and each candidate's cell) to the master and from it with every chain task; a malformed
// image or cell is refused with a FarmError; and a farm job equals the embedded render bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "farm/chain_codec.h"
#include "farm/error.h"
#include "farm/harness.h"
#include "image/bitmap.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;
using pf::farm::FarmError;

pf::FirstStageImage stageImage() {
    pf::FirstStageImage image;
    image.reduction = 4;
    image.width = 2;
    image.height = 1;
    image.luminance = {0.25, 3.0};
    return image;
}

TEST(FarmTwoStage, FirstStageTravelsExactlyAndMalformedOnesAreRefused) {
    pf::ChainTask task;
    task.index = 3;
    task.mutations = 10;
    task.firstStage = stageImage();
    const pf::ChainTask back = pf::farm::fromProto(pf::farm::toProto(task));
    EXPECT_EQ(back.firstStage.reduction, 4);
    EXPECT_EQ(back.firstStage.width, 2);
    EXPECT_EQ(back.firstStage.height, 1);
    EXPECT_EQ(back.firstStage.luminance, task.firstStage.luminance);
    EXPECT_FALSE(pf::farm::fromProto(pf::farm::toProto(pf::ChainTask{})).firstStage.enabled());
    const auto refused = [&](const std::function<void(v1::ChainTask &)> &spoil) {
        v1::ChainTask wire = pf::farm::toProto(task);
        spoil(wire);
        EXPECT_THROW(pf::farm::fromProto(wire), FarmError) << wire.DebugString();
    };
    refused([](auto &w) { w.mutable_first_stage()->set_width(3); });
    refused([](auto &w) { w.mutable_first_stage()->set_luminance(0, 0.0); });
    refused([](auto &w) { w.mutable_first_stage()->set_luminance(1, std::nan("")); });
    refused([](auto &w) { w.mutable_first_stage()->set_height(0); });

    // A seeding result: the sums and each candidate's cell.
    const auto scene = pf::loadScene(writeTestScene(tempDir("wire-two-stage"), 8, 1));
    const pf::Film &film = scene->sensor().film();
    pf::SeedingResult seeding;
    seeding.candidates = {{{0, 0, 0, 3}, 0.5, 1}, {{9, 2, 1, 2}, 0.25, 0}};
    seeding.depthLuminance = {0.0, 0.0, 0.75};
    seeding.firstStage = stageImage();  // 2 x 2 cells of 4 x 4 pixels cover the 8 x 8 film
    seeding.firstStage.height = 2;
    seeding.firstStage.luminance = {0.0, 2.0, 1.0, 0.5};  // sums may be zero; the normalizer floors them
    const pf::SeedingTask seedingTask{0, 64, 0};
    const pf::SeedingResult decoded =
        pf::farm::decodeSeedingResult(pf::farm::encodeSeedingResult(seeding), film, seedingTask);
    ASSERT_EQ(decoded.candidates.size(), 2u);
    EXPECT_EQ(decoded.candidates[0].cell, 1u);
    EXPECT_EQ(decoded.candidates[1].cell, 0u);
    EXPECT_EQ(decoded.firstStage.luminance, seeding.firstStage.luminance);
    const auto refusedSeeding = [&](const std::function<void(v1::SeedingOutput &)> &spoil) {
        v1::SeedingOutput wire;
        ASSERT_TRUE(wire.ParseFromString(pf::farm::encodeSeedingResult(seeding)));
        spoil(wire);
        EXPECT_THROW(pf::farm::decodeSeedingResult(wire.SerializeAsString(), film, seedingTask), FarmError)
            << wire.DebugString();
    };
    refusedSeeding([](auto &w) { w.mutable_candidates()->set_cell(0, 4); });
    refusedSeeding([](auto &w) { w.mutable_candidates()->mutable_cell()->RemoveLast(); });
    refusedSeeding([](auto &w) { w.mutable_first_stage()->set_luminance(0, -1.0); });
    refusedSeeding([](auto &w) { w.clear_first_stage(); });
    refusedSeeding([](auto &w) { w.mutable_first_stage()->set_reduction(2); });  // 8 x 8 film: 4 x 4 cells
}

class FarmTwoStageJobs : public FarmTest {};

TEST_F(FarmTwoStageJobs, MatchTheEmbeddedRenderBitForBit) {
    // 80 x 80 pixels: 16 seeding tasks of 400 pixels (render/seeding.cpp) whose first stages (10 x 10 cells) the
    // master sums.
    const std::string scene = writeTestScene(farm->dir() + "/scene", 80, 8);
    farm->startMaster(kFastLeases);
    farm->startWorker(2);
    for (const char *integrator : {"pssmlt", "mlt"}) {
        SCOPED_TRACE(integrator);
        const std::string spec = std::string("--integrator ") + integrator +
                                 " --spp 8 --seed 5 -P maxDepth=4 -P luminanceSamples=20000 -P directSamples=4"
                                 " -P twoStage=true -P firstStageSizeReduction=8";
        const std::string ref = farm->embeddedRender(scene, spec, std::string("ref-") + integrator);
        const std::string out = farm->dir() + "/" + integrator + ".exr";
        const auto [code, output] = farm->cli("submit " + scene + " " + spec + " --wait -o " + out);
        ASSERT_EQ(code, 0) << output << farm->master().log();
        EXPECT_TRUE(sameBits(ref, out));
        const v1::Job job = farm->waitForJob(jobIdFrom(output), 10s);
        ASSERT_EQ(job.state(), v1::JOB_DONE);
        EXPECT_EQ(job.chain().seeding_tasks(), 16u);
        EXPECT_GT(job.chain().luminance(), 0);
        // The one-stage render of the same seed differs: the chains ran on another target.
        const std::string oneStage =
            farm->embeddedRender(scene,
                                 std::string("--integrator ") + integrator +
                                     " --spp 8 --seed 5 -P maxDepth=4 -P luminanceSamples=20000 -P directSamples=4",
                                 std::string("one-") + integrator);
        EXPECT_FALSE(sameBits(oneStage, out));
    }
}

}  // namespace
}  // namespace pf::test::farm
