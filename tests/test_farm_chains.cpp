// Markov-chain jobs on the farm (ARCHITECTURE.md "A job, end to end"): seeding tasks, the normalizer,
// chain tasks and the direct component, with real master and worker processes on loopback. The farm
// image equals the embedded `pathfarm render` of the same spec and seed bit for bit (every component is
// merged in task order on both sides), also when a worker is killed (SIGKILL) inside a chain task and the
// master is killed and restarted in the chain phase; no task is merged twice.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <filesystem>

#include "farm/harness.h"
#include "image/bitmap.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

class FarmChains : public FarmTest {
protected:
    // Every task of the job was merged exactly once (the store's merges name each task once).
    void expectMergedOnce(int64_t id, int64_t tasks) {
        const std::string job = std::to_string(id);
        EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + job), tasks);
        EXPECT_EQ(farm->queryStore("SELECT COUNT(DISTINCT task_idx) FROM merges WHERE job_id = " + job), tasks);
        EXPECT_EQ(farm->queryStore("SELECT MAX(task_idx) FROM merges WHERE job_id = " + job), tasks - 1);
    }
};

struct Case {
    const char *integrator;
    const char *args;
    uint64_t sparseSeedingSamples = 0;  // > 0: luminanceSamples below one per pixel (render/seeding.h)
};

// 80 x 80 pixels: 16 seeding tasks (400 pixels each, render/seeding.cpp), a direct component of 4 samples per
// pixel in four image tasks between the chain tasks of 16384 mutations. ERPT: the luminance pilot, the direct
// component, then 8 rounds of burst passes (one seed sample per pixel and round). mmlt seeds sparsely: 900
// luminance samples make runs of 7 pixels, cut at the end of each seeding task (16 x 58 runs), so a task's
// candidates stay in its pixels.
const Case kCases[] = {
    {"pssmlt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4"},
    {"mlt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4"},
    {"erpt", "--spp 8 -P luminanceSamples=20000 -P directSamples=4 -P chainLength=20 -P numChains=0.5"},
    {"mmlt", "--spp 8 -P luminanceSamples=900 -P directSamples=4", 16 * 58},
};

TEST_F(FarmChains, ChainJobsMatchTheEmbeddedRenderBitForBit) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 80, 8);
    farm->startMaster(kFastLeases);
    farm->startWorker(2);
    farm->startWorker(1);
    for (const Case &c : kCases) {
        SCOPED_TRACE(c.integrator);
        const std::string spec = std::string("--integrator ") + c.integrator + " " + c.args + " --seed 7 -P maxDepth=4";
        const std::string ref = farm->embeddedRender(scene, spec, std::string("ref-") + c.integrator);
        const std::string out = farm->dir() + "/" + c.integrator + ".exr";
        const auto [code, output] = farm->cli("submit " + scene + " " + spec + " --wait -o " + out);
        ASSERT_EQ(code, 0) << output << farm->master().log();
        EXPECT_TRUE(sameBits(ref, out));
        EXPECT_EQ(readEXR(out).metadata.at("pathfarm.integrator"), c.integrator);

        const v1::Job job = farm->waitForJob(jobIdFrom(output), 10s);
        ASSERT_EQ(job.state(), v1::JOB_DONE);
        const v1::ChainStats &chain = job.chain();
        EXPECT_EQ(chain.phase(), v1::CHAIN_PHASE_CHAINS);
        // Bursts seed with the luminance pilot alone and sample their seeds in their own tasks; the others
        // split 80 x 80 pixels into 16 seeding tasks (render/seeding.cpp).
        const bool bursts = std::string(c.integrator) == "erpt";
        EXPECT_EQ(chain.seeding_tasks(), bursts ? 1u : 16u);
        EXPECT_EQ(chain.direct_tasks(), 4u);  // one sample per pixel each at 80², between the passes
        EXPECT_GT(chain.luminance(), 0);
        EXPECT_EQ(chain.candidates() > 0u, !bursts);
        EXPECT_GT(chain.mutations(), 0u);
        ASSERT_GT(chain.mutation_counts_size(), 0);
        uint64_t proposed = 0, accepted = 0;
        for (const v1::MutationCount &m : chain.mutation_counts()) {
            proposed += m.proposed();
            accepted += m.accepted();
            EXPECT_GE(m.acceptance(), 0);
            EXPECT_LE(m.acceptance(), 1);
        }
        EXPECT_GT(proposed, 0u);
        EXPECT_GT(accepted, 0u);
        // Each kind of work in its unit: BDPT samples of the whole seeding, pixel samples of the
        // direct component (directSamples=4), mutations of the chains; Job.samples are pixel samples only.
        constexpr uint64_t kPixels = 80 * 80;
        EXPECT_GT(chain.seeding_samples_per_pixel(), 0);
        if (bursts) {
            // The pilot's 20000 samples, then one seed sample per pixel and round (--spp 8), in whole passes.
            EXPECT_EQ(chain.seeding_samples(), 20000 + kPixels * 8);
            EXPECT_GT(chain.passes(), 0u);
            EXPECT_EQ(1 + 4 + chain.passes() * chain.tasks_per_pass(), static_cast<uint64_t>(job.tasks().total()));
        } else if (c.sparseSeedingSamples > 0) {
            EXPECT_EQ(chain.seeding_samples(), c.sparseSeedingSamples);
        } else {
            EXPECT_EQ(chain.seeding_samples(), kPixels * static_cast<uint64_t>(chain.seeding_samples_per_pixel()));
        }
        EXPECT_EQ(chain.direct_samples_per_pixel(), 4);
        EXPECT_EQ(chain.direct_samples(), kPixels * 4);
        EXPECT_EQ(job.samples(), chain.seeding_samples() + chain.direct_samples());
        EXPECT_EQ(chain.mutations_per_pixel(), static_cast<int64_t>(chain.mutations() / kPixels));
        EXPECT_EQ(job.samples_per_pixel(), chain.mutations_per_pixel());  // the budget's unit, as before
        EXPECT_GT(job.tasks().total(), 3);
        expectMergedOnce(job.id(), job.tasks().total());
    }
}

// On a film of 2^18 pixels or more the direct component's tasks grow to several samples per pixel
// (render/chain_job.h): at 512² to 2, so directSamples=4 makes tasks of 1, 1 and 2, which the farm merges to the
// embedded render's bits.
TEST_F(FarmChains, DirectTasksOfSeveralSamplesMatchTheEmbeddedRender) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 512, 8);
    farm->startMaster();
    farm->startWorker(2);
    std::string out, ref;
    const v1::Job job = farm->submitMatchingEmbedded(
        scene,
        "--integrator erpt --spp 1 --seed 3 -P maxDepth=3 -P luminanceSamples=2000 -P directSamples=4 -P "
        "chainLength=5",
        out, ref);
    EXPECT_EQ(job.chain().direct_tasks(), 3u);
    EXPECT_EQ(job.chain().direct_samples_per_pixel(), 4);
    EXPECT_EQ(job.chain().direct_samples(), 512u * 512u * 4u);
    EXPECT_EQ(1 + 3 + job.chain().passes() * job.chain().tasks_per_pass(), static_cast<uint64_t>(job.tasks().total()));
    expectMergedOnce(job.id(), job.tasks().total());
}

TEST_F(FarmChains, KilledWorkerAndRestartedMasterInTheChainPhaseDoNotChangeTheImage) {
    // 64 x 64 pixels, 96 mutations per pixel: 24 MLT chain tasks of 16384 mutations after the seeding.
    const std::string scene = writeTestScene(farm->dir() + "/scene", 64, 8);
    const std::string spec = "--integrator mlt --spp 96 --seed 3 -P maxDepth=4 -P luminanceSamples=20000";
    const std::string ref = farm->embeddedRender(scene, spec, "reference");
    farm->startMaster(kFastLeases);
    const auto [code, output] = farm->cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    const std::string job = std::to_string(id);

    // A worker alone with the job is killed inside a chain task. Its uploads wait a quarter of a second, so that the
    // kill lands before the chain task's result is delivered even when the task (16384 mutations, tens of
    // milliseconds) ends before this test sees its log line (a loaded suite run once saw no expired attempt).
    Process &victim = farm->startWorker(1, {"--upload-delay", "0.25"});
    ASSERT_TRUE(waitUntil([&] { return victim.log().find("rendering chain task") != std::string::npos; }, 120s))
        << victim.log() << farm->master().log();
    victim.signal(SIGKILL);
    victim.wait(10s);

    // Another worker carries on until chain results are checkpointed; then the master is killed.
    farm->startWorker(2);
    ASSERT_TRUE(waitUntil(
        [&] {
            return farm->queryStore(
                       "SELECT COUNT(*) FROM merges m JOIN tasks t ON t.job_id = m.job_id AND "
                       "t.idx = m.task_idx WHERE t.kind = 'chain' AND m.job_id = " +
                       job) >= 2;
        },
        120s))
        << farm->master().log();
    farm->killMaster();
    farm->startMaster(kFastLeases);

    const v1::Job done = farm->waitForJob(id, 240s);
    ASSERT_EQ(done.state(), v1::JOB_DONE) << done.DebugString() << farm->master().log();
    EXPECT_GE(done.tasks().expired_attempts(), 1);
    EXPECT_EQ(done.chain().phase(), v1::CHAIN_PHASE_CHAINS);
    const auto [fcode, fetched] = farm->cli("fetch " + job + " -o " + farm->dir() + "/farm.exr");
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(ref, farm->dir() + "/farm.exr"));
    // Seeding (16 tasks at 64²), direct component (16 tasks of one sample per pixel), 24 chain tasks.
    EXPECT_EQ(done.tasks().total(), 56);
    expectMergedOnce(id, 56);
}

TEST_F(FarmChains, TimeBudgetIssuesWholeChainTasks) {
    // 64 x 64 pixels: a chain task is 16384 mutations, 4 per pixel, whatever the budget, so a timed job of
    // n chain tasks and d direct samples per pixel (which keep the pace of a render of the scene's
    // sampleCount: 2 per chain task here) has the bits of an spp job of 4n mutations per pixel with
    // directSamples = d.
    const std::string scene = writeTestScene(farm->dir() + "/scene", 64, 8);
    farm->startMaster();
    farm->startWorker(2);
    const std::string args = "--integrator mlt --seed 5 -P maxDepth=4 -P luminanceSamples=20000 -P directSamples=4";
    const std::string out = farm->dir() + "/timed.exr";
    const auto [code, output] = farm->cli("submit " + scene + " " + args + " --time 2 --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    const Bitmap img = readEXR(out);
    const int mpp = std::stoi(img.metadata.at("pathfarm.spp"));
    EXPECT_GE(mpp, 4);
    EXPECT_EQ(mpp % 4, 0);
    const double seconds = std::stod(img.metadata.at("pathfarm.renderSeconds"));
    EXPECT_GT(seconds, 1.0);
    const v1::Job job = farm->waitForJob(jobIdFrom(output), 10s);
    const int64_t direct = job.chain().direct_samples_per_pixel();
    EXPECT_EQ(direct, 2 * (mpp / 4));
    EXPECT_EQ(job.tasks().total(), 16 + direct + mpp / 4);  // seeding (16 tasks at 64²), direct component, chains
    expectMergedOnce(job.id(), job.tasks().total());
    EXPECT_TRUE(sameBits(
        farm->embeddedRender(
            scene, args + " --spp " + std::to_string(mpp) + " -P directSamples=" + std::to_string(direct), "reference"),
        out));
}

// A burst job under a time budget runs whole passes (render/burst.h): the farm's image has the bits of
// `pathfarm render --passes P` with the P passes the job ran, also when a worker is killed (SIGKILL) in the
// middle of a pass; every task is merged once.
TEST_F(FarmChains, TimedBurstJobEqualsItsPassesEmbeddedAfterAWorkerDies) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 64, 8);
    farm->startMaster(kFastLeases);
    Process &victim = farm->startWorker(1);
    farm->startWorker(1);
    const std::string args =
        "--integrator erpt --seed 9 -P maxDepth=4 -P directSamples=2 -P chainLength=40 "
        "-P numChains=8.0 -P passMutations=8192";
    const auto [code, output] = farm->cli("submit " + scene + " " + args + " --time 4");
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    ASSERT_TRUE(waitUntil([&] { return victim.log().find("rendering chain task") != std::string::npos; }, 60s))
        << victim.log() << farm->master().log();
    victim.signal(SIGKILL);
    victim.wait(10s);
    const v1::Job job = farm->waitForJob(id, 120s);
    ASSERT_EQ(job.state(), v1::JOB_DONE) << farm->master().log();
    const uint64_t passes = job.chain().passes();
    ASSERT_GT(passes, 1u);
    EXPECT_EQ(job.chain().passes() * job.chain().tasks_per_pass() + 1 + job.chain().direct_samples_per_pixel(),
              static_cast<uint64_t>(job.tasks().total()));
    const std::string out = farm->dir() + "/timed.exr";
    const auto [fcode, fetched] = farm->cli("fetch " + std::to_string(id) + " -o " + out);
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(farm->embeddedRender(scene, args + " --passes " + std::to_string(passes), "passes"), out));
    expectMergedOnce(id, job.tasks().total());
}

// What the luminance pilot tunes (lambda and manifoldMediumAngle = "auto", integrators/erpt.h) travels from the
// pilot's seeding result through the master to every chain task: an mept job on the glass egg filled with a
// forward-scattering medium (scenes/glass-egg, 24 x 24) equals the embedded render bit for bit, and the job
// record and both images carry the same λ and dtheta.
TEST_F(FarmChains, PilotTunedLambdaAndMediumAngleReachEveryChainTask) {
    const std::string dir = farm->dir() + "/scene";
    std::filesystem::copy(std::string(PATHFARM_SOURCE_DIR) + "/scenes/glass-egg", dir,
                          std::filesystem::copy_options::recursive);
    const std::string scene = dir + "/scene.xml";
    farm->startMaster();
    farm->startWorker(2);
    const std::string spec =
        "--integrator mept --spp 2 --seed 7 -D res=24 -D lightScale=0.5 -P maxDepth=6 -P luminanceSamples=4096 "
        "-P directSamples=1 -P chainLength=20 -P lambda=auto -P manifoldMediumAngle=auto";
    std::string out, ref;
    const v1::Job job = farm->submitMatchingEmbedded(scene, spec, out, ref);
    ASSERT_EQ(job.state(), v1::JOB_DONE);
    const double lambda = job.chain().lambda(), angle = job.chain().medium_angle();
    std::printf("pilot: lambda %.2f, dtheta %.3f degrees\n", lambda, angle * 180 / M_PI);
    EXPECT_GT(lambda, 0);
    EXPECT_GT(angle, 0);
    EXPECT_LT(angle, M_PI / 2);
    for (const std::string &image : {ref, out}) {
        const auto metadata = readEXR(image).metadata;
        EXPECT_EQ(metadata.at("pathfarm.lambda"), std::to_string(lambda)) << image;
        EXPECT_EQ(metadata.at("pathfarm.mediumAngle"), std::to_string(angle * 180 / M_PI)) << image;
    }
}

TEST_F(FarmChains, BadChainBudgetsAreRefusedAtSubmission) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 16, 8);
    farm->startMaster();
    // A chain parameter out of range is an error for the submitter, naming the parameter.
    const auto [code, output] = farm->cli("submit " + scene + " --integrator erpt --spp 3 -P chainLength=0");
    EXPECT_NE(code, 0) << output;
    EXPECT_NE(output.find("chainLength"), std::string::npos) << output;
    EXPECT_TRUE(farm->master().running());
}

}  // namespace
}  // namespace pf::test::farm
