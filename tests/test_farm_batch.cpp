// Batched results (issue 17): a worker leases image tasks (or a chain job's chain tasks) that follow each other
// in a job, merges their film blocks (chain results) in task order and returns one result naming every
// attempt, so that the master decodes and merges one film for all of them. Checked here: the image equals the embedded
// render up to the rounding of the batch's own sum (it is added to the film as one block, not task by task), every task
// is merged exactly once (also under a time budget), a batch that is out of order, repeats an attempt, names another
// worker's attempt or comes again is refused whole, and a worker that goes silent holding a batch, or a master restart
// with a batch waiting for its turn, loses no work. A chain batch passes over the direct tasks between its chain tasks.
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <thread>

#include "batch_governor.h"
#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/convert.h"
#include "farm/fake_worker.h"
#include "farm/harness.h"
#include "farm/job_setup.h"
#include "image/bitmap.h"
#include "integrators/integrator.h"
#include "render/chain_job.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "runtime.h"
#include "scene/scene.h"
#include "support/process.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

constexpr int kSpp = 64;  // eight tasks of 8 samples (render/image_task.h)
const std::string kSpec = "--spp 64 --seed 2";

// Pixels of two images agree up to a few float ulps: a batch's sum of doubles rounds differently from
// the task-by-task merge in its last bits, which the float EXR mostly hides. Returns how many pixel
// values differ at all.
int64_t expectEqualUpToRounding(const std::string &exrA, const std::string &exrB) {
    const Bitmap a = readEXR(exrA), b = readEXR(exrB);
    EXPECT_EQ(a.rgb.size(), b.rgb.size());
    int64_t differ = 0;
    for (size_t i = 0; i < std::min(a.rgb.size(), b.rgb.size()); ++i) {
        const float x = a.rgb[i], y = b.rgb[i];
        differ += x != y;
        EXPECT_LE(std::abs(x - y), 4 * 6e-8f * std::max(std::abs(x), std::abs(y))) << "value " << i;
    }
    return differ;
}

// Every issued task of the job merged exactly once.
void expectMergedOnce(const Farm &farm, int64_t job, int64_t tasks) {
    const std::string where = " FROM merges WHERE job_id = " + std::to_string(job);
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*)" + where), tasks);
    EXPECT_EQ(farm.queryStore("SELECT COUNT(DISTINCT task_idx)" + where), tasks);
}

// Film blocks of the test scene's tasks as a worker renders them, summed in task order: what a batch
// of `tasks` carries.
class Blocks {
public:
    explicit Blocks(const std::string &scene)
        : loaded_(loadScene(scene)), integrator_(createIntegrator("path", loaded_->integratorProperties(), true)) {}
    std::string batch(const std::vector<v1::TaskSpec> &tasks) const {
        std::optional<ImageBlock> sum;
        for (const v1::TaskSpec &t : tasks) {
            ImageTaskResult r = runImageTask(*loaded_, dynamic_cast<const SamplingIntegrator &>(*integrator_), 2,
                                             ImageTask{t.image().first_sample(), t.image().sample_count()}, 1);
            if (sum) {
                sum->merge(r.block);
            } else {
                sum.emplace(std::move(r.block));
            }
        }
        return pf::farm::encodeBlock(*sum);
    }

private:
    std::unique_ptr<Scene> loaded_;
    std::unique_ptr<Integrator> integrator_;
};

// The payload a worker returns for any task of a Markov-chain job, computed here as pathfarm-worker does,
// and for a run of chain tasks their results summed in task order (worker/chain_batch.h).
class ChainPayloads {
public:
    ChainPayloads(const std::string &scene, const v1::TaskSpec &any)
        : loaded_(loadScene(scene)),
          integrator_(makeIntegrator(*loaded_, any.job().integrator(), pf::farm::toNameValues(any.job().params()))),
          chains_(dynamic_cast<const ChainIntegrator &>(*integrator_)) {}
    std::string payload(const std::vector<v1::TaskSpec> &tasks) const {
        const v1::TaskSpec &t = tasks.front();
        const uint64_t seed = t.job().seed();
        if (t.has_seeding())
            return pf::farm::encodeSeedingResult(
                chains_.runSeeding(*loaded_, t.job().budget().spp(), seed, pf::farm::fromProto(t.seeding())));
        if (t.has_image())
            return pf::farm::encodeBlock(
                runDirectTask(*loaded_, chains_, seed, ImageTask{t.image().first_sample(), t.image().sample_count()}, 1)
                    .block);
        ChainResult sum = runChainTask(*loaded_, chains_, seed, pf::farm::fromProto(t.chain()));
        for (size_t i = 1; i < tasks.size(); ++i)
            addChainResult(sum, runChainTask(*loaded_, chains_, seed, pf::farm::fromProto(tasks[i].chain())));
        return pf::farm::encodeChainResult(sum);
    }

private:
    std::unique_ptr<Scene> loaded_;
    std::unique_ptr<Integrator> integrator_;
    const ChainIntegrator &chains_;
};

// Leases a chain job's tasks one by one and delivers its seeding tasks' results (`payloads` set up from the first),
// until `next` holds the first task after the seeding, still leased to `w`.
void seedAndLeaseNext(FakeWorker &w, const std::string &scene, std::optional<ChainPayloads> &payloads,
                      std::vector<v1::TaskSpec> &next) {
    for (;;) {
        next = w.leaseBatch(1);
        ASSERT_EQ(next.size(), 1u);
        if (!payloads) payloads.emplace(scene, next[0]);
        if (!next[0].has_seeding()) return;
        ASSERT_TRUE(w.complete(next[0].attempt_id(), payloads->payload(next)).accepted());
    }
}

// Starts the master and submits `spec` (with seed 4 and maxDepth 4) on the 32² test scene.
void submitOnNewMaster(Farm &farm, const std::string &spec, std::string &scene, int64_t &id) {
    farm.startMaster();
    scene = writeTestScene(farm.dir() + "/scene", 32, 8);
    const auto [code, output] = farm.cli("submit " + scene + " " + spec + " --seed 4 -P maxDepth=4");
    ASSERT_EQ(code, 0) << output;
    id = jobIdFrom(output);
}

// On a started master: writes the 32² test scene, renders `spec` (with seed 4 and maxDepth 4) embedded into `ref`
// and submits it as job `id`.
void submitBesideEmbedded(Farm &farm, const std::string &spec, std::string &scene, std::string &ref, int64_t &id) {
    scene = writeTestScene(farm.dir() + "/scene", 32, 8);
    const std::string args = spec + " --seed 4 -P maxDepth=4";
    ref = farm.embeddedRender(scene, args, "ref");
    const auto [code, output] = farm.cli("submit " + scene + " " + args);
    ASSERT_EQ(code, 0) << output;
    id = jobIdFrom(output);
}

std::vector<int64_t> laterAttempts(const std::vector<v1::TaskSpec> &tasks) {
    std::vector<int64_t> out;
    for (size_t i = 1; i < tasks.size(); ++i) out.push_back(tasks[i].attempt_id());
    return out;
}

// Job `id` ends done, every task merged once, and its image equals `ref` up to rounding. `job`: the finished job.
void expectDoneAsEmbedded(Farm &farm, int64_t id, const std::string &ref, v1::Job &job) {
    job = farm.waitForJob(id, 60s);
    ASSERT_EQ(job.state(), v1::JOB_DONE) << farm.master().log();
    expectMergedOnce(farm, id, job.tasks().total());
    const std::string out = farm.dir() + "/farm.exr";
    const auto [fetched, log] = farm.cli("fetch " + std::to_string(id) + " -o " + out);
    ASSERT_EQ(fetched, 0) << log;
    expectEqualUpToRounding(ref, out);
}

// Leases job `id`'s tasks left through `w`, `batch` at a time, delivers them, and expects the job done as the
// embedded render `ref` (expectDoneAsEmbedded).
void finishChainJob(Farm &farm, FakeWorker &w, const ChainPayloads &payloads, int64_t id, int batch,
                    const std::string &ref, v1::Job &job) {
    for (std::vector<v1::TaskSpec> rest = w.leaseBatch(batch); !rest.empty(); rest = w.leaseBatch(batch))
        ASSERT_TRUE(w.complete(rest[0].attempt_id(), payloads.payload(rest), grpc::StatusCode::OK, laterAttempts(rest))
                        .accepted());
    expectDoneAsEmbedded(farm, id, ref, job);
}

// A job of the test scene, its embedded render, and the fetched farm image.
struct Job {
    Job(const Farm &farm, int res)
        : scene(writeTestScene(farm.dir() + "/scene", res, kSpp)),
          reference(farm.embeddedRender(scene, kSpec, "embedded")) {
        const auto [code, output] = farm.cli("submit " + scene + " " + kSpec);
        EXPECT_EQ(code, 0) << output;
        id = jobIdFrom(output);
    }
    std::string fetch(const Farm &farm) const {
        EXPECT_EQ(farm.waitForJob(id, 60s).state(), v1::JOB_DONE);
        const std::string out = farm.dir() + "/farm.exr";
        const auto [code, output] = farm.cli("fetch " + std::to_string(id) + " -o " + out);
        EXPECT_EQ(code, 0) << output;
        return out;
    }
    std::string scene, reference;
    int64_t id = -1;
};

// A batch size other than auto or 1..1024 is refused at start-up with an error naming the flag, before the worker
// connects anywhere.
TEST(WorkerBatchFlag, OutOfRangeIsRefusedNamingTheFlag) {
    for (const std::string bad : {"0", "1025", "x"}) {
        const ProcessResult r = runCommand(std::string(PATHFARM_WORKER_BIN) +
                                           " --master 127.0.0.1:1 --token-file /dev/null --batch " + bad + " 2>&1");
        EXPECT_NE(r.exitCode, 0) << bad;
        EXPECT_NE(r.output.find("--batch"), std::string::npos) << r.output;
    }
}

// The master's batch governor settings out of range, or not numbers, are refused at start-up with an error naming
// the flag, before the master opens its data directory or listens.
TEST(MasterBatchFlags, OutOfRangeIsRefusedNamingTheFlag) {
    for (const auto &[flag, bad] : std::vector<std::pair<std::string, std::string>>{
             {"--batch-busy", "-1"}, {"--batch-busy", "x"}, {"--batch-window-ms", "5"}, {"--batch-window-ms", "x"}}) {
        const ProcessResult r = runCommand("timeout 20 " + std::string(PATHFARM_MASTER_BIN) +
                                           " --listen 127.0.0.1:0 --data /nonexistent/pathfarm --token-file /dev/null"
                                           " --worker-token-file /dev/null " +
                                           flag + " " + bad + " 2>&1");
        EXPECT_NE(r.exitCode, 0) << flag << " " << bad;
        EXPECT_NE(r.exitCode, 124) << flag << " " << bad << ": the master started";
        EXPECT_NE(r.output.find(flag), std::string::npos) << r.output;
    }
}

// The governor (master/batch_governor.h) on a clock of its own: the batch doubles after each window in which
// taking results used more than the busy share of a core, halves after one below a fifth of it, and stays
// between 1 and its most.
TEST(BatchGovernor, GrowsWhileBusyAndShrinksWhenIdle) {
    using namespace std::chrono;
    master::BatchGovernor g(0.5, 1000ms, 8);
    auto now = master::BatchGovernor::Clock::now();
    EXPECT_EQ(g.batch(now), 1);
    const std::vector<std::pair<double, int>> windows = {{0.8, 2}, {0.6, 4},  {0.45, 4}, {0.7, 8}, {0.9, 8},
                                                         {0.2, 8}, {0.05, 4}, {0.09, 2}, {0.0, 1}, {0.0, 1}};
    for (const auto &[cpu, expected] : windows) {
        // Spread over the window: what counts is its sum.
        for (int i = 0; i < 4; ++i) g.record(cpu / 4, now + milliseconds(250 * i));
        now += 1000ms;
        EXPECT_EQ(g.batch(now), expected) << "after a window with " << cpu << " CPU s";
    }
}

// What the master takes for a result's rendering time when it finds its transfer time: a batch of chain tasks ran
// one per thread at once, so its summed seconds are divided by the tasks that ran side by side; anything else
// rendered for its seconds.
TEST(RenderWallSeconds, AChainBatchRanOnePerThread) {
    v1::TaskStats stats;
    stats.set_seconds(12);
    v1::TaskSpec chain, image;
    chain.mutable_chain();
    image.mutable_image()->set_sample_count(8);
    EXPECT_DOUBLE_EQ(master::renderWallSeconds(chain, 8, 4, stats), 3.0);
    EXPECT_DOUBLE_EQ(master::renderWallSeconds(chain, 3, 4, stats), 4.0);   // three tasks on three of four threads
    EXPECT_DOUBLE_EQ(master::renderWallSeconds(chain, 8, 0, stats), 12.0);  // threads unknown: one at a time
    EXPECT_DOUBLE_EQ(master::renderWallSeconds(chain, 1, 4, stats), 12.0);
    EXPECT_DOUBLE_EQ(master::renderWallSeconds(image, 8, 4, stats), 12.0);  // image batches render one after another
}

// A worker that leaves the batch to the master (the default) gets one task per lease from an idle master,
// so the farm's image equals the embedded render bit for bit.
TEST_F(FarmTest, AnIdleMasterLeasesOneTaskToAutoBatchWorkers) {
    farm->startMaster();
    const Job job(*farm, 24);
    farm->startWorker(2);
    const std::string out = job.fetch(*farm);
    EXPECT_EQ(expectEqualUpToRounding(job.reference, out), 0);
    expectMergedOnce(*farm, job.id, kSpp / 8);
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM results WHERE bytes = 0"), 0);
}

// A master whose busy share is 0 grows its batches after every window of 50 ms: a default worker then
// returns batched results, merged once each and equal to the embedded render up to rounding.
TEST_F(FarmTest, ABusyMasterBatchesAutoBatchWorkers) {
    farm->startMaster({"--batch-busy", "0", "--batch-window-ms", "50"});
    const Job job(*farm, 24);
    const std::string scene2 = writeTestScene(farm->dir() + "/scene2", 24, 8 * kSpp);
    const auto [code, output] = farm->cli("submit " + scene2 + " --spp 512 --seed 3");
    ASSERT_EQ(code, 0) << output;
    const int64_t second = jobIdFrom(output);
    farm->startWorker(2);
    const std::string out = job.fetch(*farm);
    expectEqualUpToRounding(job.reference, out);
    expectMergedOnce(*farm, job.id, kSpp / 8);
    const v1::Job done = farm->waitForJob(second, 60s);
    EXPECT_EQ(done.state(), v1::JOB_DONE);
    expectMergedOnce(*farm, second, done.tasks().merged());
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM tasks WHERE job_id = " + std::to_string(second)),
              done.tasks().merged());
    EXPECT_GT(farm->queryStore("SELECT COUNT(*) FROM results WHERE bytes = 0"), 0);
}

TEST_F(FarmTest, ABatchingWorkerRendersTheEmbeddedImageUpToRounding) {
    farm->startMaster();
    const Job job(*farm, 24);
    farm->startWorker(2, {"--batch", "4"});
    const std::string out = job.fetch(*farm);
    expectEqualUpToRounding(job.reference, out);
    expectMergedOnce(*farm, job.id, kSpp / 8);
    // The worker batched: a batch's later tasks are stored without bytes of their own.
    EXPECT_GT(farm->queryStore("SELECT COUNT(*) FROM results WHERE bytes = 0"), 0);
}

TEST_F(FarmTest, ATimeBudgetWithBatchesMergesEveryIssuedTaskOnce) {
    farm->startMaster();
    const std::string scene = writeTestScene(farm->dir() + "/scene", 16, kSpp);
    farm->startWorker(2, {"--batch", "4"});
    const auto [code, output] = farm->cli("submit " + scene + " --time 1 --seed 2");
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    const v1::Job done = farm->waitForJob(id, 60s);
    ASSERT_EQ(done.state(), v1::JOB_DONE);
    EXPECT_GT(done.tasks().merged(), 1);
    expectMergedOnce(*farm, id, done.tasks().merged());
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM tasks WHERE job_id = " + std::to_string(id)),
              done.tasks().merged());
    // Before any task's time is known a timed job's batch holds one task, so task 1 came in a result of its
    // own (a batch's later tasks are stored without bytes).
    EXPECT_GT(farm->queryStore("SELECT bytes FROM results WHERE task_idx = 1 AND job_id = " + std::to_string(id)), 0);
}

TEST_F(FarmTest, ABatchIsTakenWholeOnceOrRefused) {
    farm->startMaster();
    const Job job(*farm, 16);
    const Blocks blocks(job.scene);
    FakeWorker w1(*farm), w2(*farm);
    const std::vector<v1::TaskSpec> batch = w1.leaseBatch(3), other = w2.leaseBatch(1);
    ASSERT_EQ(batch.size(), 3u);
    ASSERT_EQ(other.size(), 1u);
    for (size_t i = 0; i < batch.size(); ++i) EXPECT_EQ(batch[i].task_index(), batch[0].task_index() + int64_t(i));
    const std::string payload = blocks.batch(batch);
    const int64_t a0 = batch[0].attempt_id(), a1 = batch[1].attempt_id(), a2 = batch[2].attempt_id();
    const int64_t foreign = other[0].attempt_id();

    // Out of order, an attempt twice: refused as a bad request, nothing stored.
    w1.complete(a0, payload, grpc::StatusCode::INVALID_ARGUMENT, {a2, a1});
    EXPECT_NE(w1.lastError().find("is not image task"), std::string::npos) << w1.lastError();
    w1.complete(a0, payload, grpc::StatusCode::INVALID_ARGUMENT, {a1, a1});
    // Another worker's attempt, in either direction: ignored whole.
    v1::CompleteReply r = w1.complete(a0, payload, grpc::StatusCode::OK, {a1, a2, foreign});
    EXPECT_FALSE(r.accepted());
    EXPECT_NE(r.reason().find("was not leased to worker"), std::string::npos) << r.reason();
    r = w2.complete(foreign, payload, grpc::StatusCode::OK, {a0});
    EXPECT_FALSE(r.accepted());
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM results"), 0);

    // The batch itself, once; again, or one of its tasks alone, is superseded.
    EXPECT_TRUE(w1.complete(a0, payload, grpc::StatusCode::OK, {a1, a2}).accepted());
    r = w1.complete(a0, payload, grpc::StatusCode::OK, {a1, a2});
    EXPECT_FALSE(r.accepted());
    EXPECT_NE(r.reason().find("superseded"), std::string::npos) << r.reason();
    EXPECT_FALSE(w1.complete(a1, blocks.batch({batch[1]})).accepted());
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM results"), 3);

    EXPECT_TRUE(w2.complete(foreign, blocks.batch(other)).accepted());
    for (std::vector<v1::TaskSpec> rest = w2.leaseBatch(64); !rest.empty(); rest = w2.leaseBatch(64))
        EXPECT_TRUE(w2.complete(rest[0].attempt_id(), blocks.batch(rest), grpc::StatusCode::OK, laterAttempts(rest))
                        .accepted());
    expectEqualUpToRounding(job.reference, job.fetch(*farm));
    expectMergedOnce(*farm, job.id, kSpp / 8);
}

TEST_F(FarmTest, AWorkerThatGoesSilentHoldingABatchLosesNoWork) {
    farm->startMaster(kFastLeases);
    const Job job(*farm, 16);
    {
        // Leases four tasks and is never heard of again (as a killed worker), so they expire.
        FakeWorker silent(*farm);
        ASSERT_EQ(silent.leaseBatch(4).size(), 4u);
    }
    farm->startWorker(2, {"--batch", "3"});
    expectEqualUpToRounding(job.reference, job.fetch(*farm));
    expectMergedOnce(*farm, job.id, kSpp / 8);
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'expired'"), 4);
}

TEST_F(FarmTest, ABatchWaitingForItsTurnSurvivesAMasterRestart) {
    farm->startMaster(kFastLeases);
    const Job job(*farm, 16);
    const Blocks blocks(job.scene);
    FakeWorker first(*farm), batcher(*farm);
    const auto head = first.leaseBatch(1);
    const auto batch = batcher.leaseBatch(3);
    ASSERT_EQ(head.size(), 1u);
    ASSERT_EQ(batch.size(), 3u);
    // Accepted, but it waits on disk for task 0, which the master's restart finds still leased.
    EXPECT_TRUE(batcher.complete(batch[0].attempt_id(), blocks.batch(batch), grpc::StatusCode::OK, laterAttempts(batch))
                    .accepted());
    farm->killMaster();
    farm->startMaster(kFastLeases);
    EXPECT_TRUE(first.complete(head[0].attempt_id(), blocks.batch(head)).accepted());
    for (std::vector<v1::TaskSpec> rest = first.leaseBatch(2); !rest.empty(); rest = first.leaseBatch(2))
        EXPECT_TRUE(first.complete(rest[0].attempt_id(), blocks.batch(rest), grpc::StatusCode::OK, laterAttempts(rest))
                        .accepted());
    expectEqualUpToRounding(job.reference, job.fetch(*farm));
    expectMergedOnce(*farm, job.id, kSpp / 8);
}

// Markov-chain jobs batch their chain tasks (never the seeding or the direct component's tasks): the worker
// sums a batch's chain results in task order, and the image equals the embedded render up to that rounding,
// with every task merged once and the same mutations, seed samples and passes.
TEST_F(FarmTest, ChainTasksBatchToTheEmbeddedImageUpToRounding) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 48, 8);
    farm->startMaster();
    farm->startWorker(2, {"--batch", "4"});
    for (const std::string args : {"--integrator mlt --spp 64 -P luminanceSamples=5000 -P directSamples=2",
                                   "--integrator erpt --spp 8 -P luminanceSamples=5000 -P directSamples=2 -P "
                                   "chainLength=20 -P passMutations=2000"}) {
        SCOPED_TRACE(args);
        const std::string spec = args + " --seed 5 -P maxDepth=4";
        const std::string ref = farm->embeddedRender(scene, spec, "ref");
        const std::string out = farm->dir() + "/farm.exr";
        const auto [code, output] = farm->cli("submit " + scene + " " + spec + " --wait -o " + out);
        ASSERT_EQ(code, 0) << output << farm->master().log();
        expectEqualUpToRounding(ref, out);
        const int64_t id = jobIdFrom(output);
        const v1::Job job = farm->waitForJob(id, 10s);
        ASSERT_EQ(job.state(), v1::JOB_DONE);
        expectMergedOnce(*farm, id, job.tasks().total());
        const std::string batched =
            "SELECT COUNT(*) FROM results r JOIN tasks t ON t.job_id = r.job_id AND t.idx = r.task_idx WHERE r.bytes = "
            "0 "
            "AND r.job_id = " +
            std::to_string(id);
        EXPECT_GT(farm->queryStore(batched + " AND t.kind = 'chain'"), 0);
        EXPECT_EQ(farm->queryStore(batched + " AND t.kind <> 'chain'"), 0);
        // The embedded render's figures: the chains' mutations per pixel and, for bursts, whole passes.
        const Bitmap embedded = readEXR(ref);
        EXPECT_EQ(std::to_string(job.chain().mutations_per_pixel()), embedded.metadata.at("pathfarm.spp"));
        EXPECT_EQ(job.chain().direct_tasks(), 2u);
        EXPECT_EQ(job.chain().seeding_tasks() + job.chain().direct_tasks() +
                      job.chain().passes() * job.chain().tasks_per_pass(),
                  static_cast<uint64_t>(job.tasks().total()));
    }
}

// Under a time budget a batch of chain tasks takes a further task only while it still ends in time on the
// worker's threads, and the job still ends with whole passes, each task merged once.
TEST_F(FarmTest, ATimedChainJobBatchesWholePassesMergedOnce) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 48, 8);
    farm->startMaster();
    farm->startWorker(2, {"--batch", "8"});
    const auto [code, output] =
        farm->cli("submit " + scene +
                  " --integrator erpt --time 3 --seed 5 -P maxDepth=4 -P luminanceSamples=5000 -P chainLength=20"
                  " -P passMutations=2000");
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    const v1::Job job = farm->waitForJob(id, 60s);
    ASSERT_EQ(job.state(), v1::JOB_DONE) << farm->master().log();
    EXPECT_GT(job.chain().passes(), 1u);
    EXPECT_GT(job.chain().mutations(), 0u);
    expectMergedOnce(*farm, id, job.tasks().total());
    const std::string chainTasks = "SELECT COUNT(*) FROM tasks WHERE kind = 'chain' AND job_id = " + std::to_string(id);
    EXPECT_EQ(static_cast<uint64_t>(farm->queryStore(chainTasks)), job.chain().passes() * job.chain().tasks_per_pass());
    EXPECT_GT(farm->queryStore("SELECT COUNT(*) FROM results WHERE bytes = 0 AND job_id = " + std::to_string(id)), 0);
}

// An image batch holds at most 64 tasks even when the worker asks for the 1024 a chain batch may hold: an image
// batch's bytes grow with its tasks' blocks.
TEST_F(FarmTest, AnImageBatchHoldsAtMost64Tasks) {
    std::string scene;
    int64_t id = -1;
    // 65536 samples per pixel in tasks of at most 256 (the master's largest task): over 256 tasks.
    ASSERT_NO_FATAL_FAILURE(submitOnNewMaster(*farm, "--integrator path --spp 65536", scene, id));
    FakeWorker w(*farm);
    const std::vector<v1::TaskSpec> batch = w.leaseBatch(master::Master::kMaxChainBatchTasks);
    ASSERT_EQ(batch.size(), static_cast<size_t>(master::Master::kMaxBatchTasks));
    for (size_t i = 0; i < batch.size(); ++i) {
        EXPECT_TRUE(batch[i].has_image());
        EXPECT_EQ(batch[i].task_index(), batch[0].task_index() + static_cast<int64_t>(i));
    }
}

// Submits an erpt job of about 800 chain tasks on a new master: 32² pixels, one burst of 20 mutations each, in
// passes of 100.
void submitManyChainTasks(Farm &farm, std::string &scene, int64_t &id) {
    ASSERT_NO_FATAL_FAILURE(submitOnNewMaster(farm,
                                              "--integrator erpt --spp 1 -P luminanceSamples=2000 -P "
                                              "directSamples=0 -P chainLength=20 -P passMutations=100",
                                              scene, id));
}

// Delivers job `id`'s seeding through `w` and leases its first chain task to `w`: that task's index, and the job's
// task count.
void seedFirstChainTask(const Farm &farm, FakeWorker &w, const std::string &scene, int64_t id, int64_t &first,
                        int64_t &total) {
    std::optional<ChainPayloads> payloads;
    std::vector<v1::TaskSpec> head;
    ASSERT_NO_FATAL_FAILURE(seedAndLeaseNext(w, scene, payloads, head));
    ASSERT_TRUE(head[0].has_chain());
    v1::GetJobRequest req;
    req.set_id(id);
    v1::Job job;
    ASSERT_TRUE(farm.clientStub()->GetJob(farm.context(farm.clientToken()).get(), req, &job).ok());
    first = head[0].task_index();
    total = job.tasks().total();
}

// A chain batch may hold more than an image batch's 64 tasks (a chain task's film covers most of the image, so only
// long batches spare the master), and under a budget in tasks no more than its worker's share of the tasks not yet
// issued: a master busy enough to batch long would otherwise lease a whole job to its first worker.
TEST_F(FarmTest, AChainBatchHoldsUpToItsWorkersShareOfTheTasksLeft) {
    std::string scene;
    int64_t id = -1, head = -1, total = 0;
    ASSERT_NO_FATAL_FAILURE(submitManyChainTasks(*farm, scene, id));
    FakeWorker first(*farm), second(*farm);
    ASSERT_NO_FATAL_FAILURE(seedFirstChainTask(*farm, first, scene, id, head, total));
    ASSERT_GT(total - head, 3 * master::Master::kMaxBatchTasks);
    // The two workers take turns; each batch is half of what is left (rounded up), in a row.
    int64_t next = head + 1, batches = 0;
    for (FakeWorker *w = &second; next < total; w = (w == &second ? &first : &second), ++batches) {
        const std::vector<v1::TaskSpec> batch = w->leaseBatch(master::Master::kMaxChainBatchTasks);
        ASSERT_EQ(static_cast<int64_t>(batch.size()), (total - next + 1) / 2) << "batch " << batches;
        for (const v1::TaskSpec &t : batch) {
            ASSERT_TRUE(t.has_chain());
            ASSERT_EQ(t.task_index(), next++);
        }
        if (batches == 0) {
            EXPECT_GT(batch.size(), static_cast<size_t>(master::Master::kMaxBatchTasks));
        }
    }
    EXPECT_GT(batches, 5);
}

// A chain batch's row passes over the direct tasks between its chain tasks (render/chain_job.h interleaves them by
// pass): the next request takes them. Its result then merges ahead of a direct task not yet merged, and no checkpoint
// may record that film (a checkpoint holds tasks [0, merged) only). Two master restarts: one with the batch waiting
// for its turn (its stored rows, split by the direct task's, join again), one with it merged ahead of the direct task.
// Every task is merged once and the image equals the embedded render up to rounding.
TEST_F(FarmTest, AChainBatchPassesOverTheDirectTasksBetweenItsChainTasks) {
    // Checkpoints are due every 300 ms; leases outlast the test's steps after each restart.
    const std::vector<std::string> flags = {"--lease-ms", "8000", "--heartbeat-ms", "250", "--checkpoint-ms", "300"};
    farm->startMaster(flags);
    std::string scene, ref;
    int64_t id = -1;
    ASSERT_NO_FATAL_FAILURE(submitBesideEmbedded(
        *farm,
        "--integrator erpt --spp 1 -P luminanceSamples=2000 -P directSamples=4 -P chainLength=20 -P passMutations=100",
        scene, ref, id));
    FakeWorker batcher(*farm), other(*farm);
    std::optional<ChainPayloads> payloads;
    // The seeding and the first direct tasks, one by one, up to the first chain task (kept leased).
    std::vector<v1::TaskSpec> head;
    for (;;) {
        head = batcher.leaseBatch(1);
        ASSERT_EQ(head.size(), 1u);
        if (!payloads) payloads.emplace(scene, head[0]);
        if (head[0].has_chain()) break;
        ASSERT_TRUE(batcher.complete(head[0].attempt_id(), payloads->payload(head)).accepted());
    }
    const std::vector<v1::TaskSpec> batch = batcher.leaseBatch(master::Master::kMaxChainBatchTasks);
    ASSERT_GT(batch.size(), 1u);
    std::vector<int64_t> passed;  // the direct tasks between the batch's chain tasks
    int64_t last = head[0].task_index();
    for (const v1::TaskSpec &t : batch) {
        ASSERT_TRUE(t.has_chain());
        ASSERT_GT(t.task_index(), last);
        for (int64_t i = last + 1; i < t.task_index(); ++i) passed.push_back(i);
        last = t.task_index();
    }
    ASSERT_FALSE(passed.empty()) << "no direct task between " << batch.front().task_index() << " and " << last;
    // The next request takes them, one at a time (a direct task is never batched).
    std::vector<std::vector<v1::TaskSpec>> direct;
    for (const int64_t index : passed) {
        direct.push_back(other.leaseBatch(master::Master::kMaxChainBatchTasks));
        ASSERT_EQ(direct.back().size(), 1u);
        EXPECT_EQ(direct.back()[0].task_index(), index);
        EXPECT_TRUE(direct.back()[0].has_image() && direct.back()[0].image().direct());
    }
    // The batch arrives before the task ahead of it, and waits on disk through a restart.
    ASSERT_TRUE(
        batcher.complete(batch[0].attempt_id(), payloads->payload(batch), grpc::StatusCode::OK, laterAttempts(batch))
            .accepted());
    farm->killMaster();
    farm->startMaster(flags);
    // Now it merges, ahead of the direct tasks, once a checkpoint is due; then a second restart.
    std::this_thread::sleep_for(400ms);
    ASSERT_TRUE(batcher.complete(head[0].attempt_id(), payloads->payload(head)).accepted());
    std::this_thread::sleep_for(400ms);
    farm->killMaster();
    farm->startMaster(flags);
    for (const std::vector<v1::TaskSpec> &d : direct)
        ASSERT_TRUE(other.complete(d[0].attempt_id(), payloads->payload(d)).accepted());
    v1::Job job;
    ASSERT_NO_FATAL_FAILURE(finishChainJob(*farm, other, *payloads, id, master::Master::kMaxChainBatchTasks, ref, job));
}

// The share counts only the workers that may run the job: a worker that runs other integrators only (or is
// blocklisted for the job) takes none of its tasks, so it does not halve the others' batches.
TEST_F(FarmTest, WorkersThatCannotRunAJobDoNotShrinkItsBatches) {
    std::string scene;
    int64_t id = -1, head = -1, total = 0;
    ASSERT_NO_FATAL_FAILURE(submitManyChainTasks(*farm, scene, id));
    FakeWorker batcher(*farm), pathOnly(*farm, {"path"});
    ASSERT_NO_FATAL_FAILURE(seedFirstChainTask(*farm, batcher, scene, id, head, total));
    const int64_t left = total - head - 1;
    ASSERT_LE(left, master::Master::kMaxChainBatchTasks);
    EXPECT_EQ(static_cast<int64_t>(batcher.leaseBatch(master::Master::kMaxChainBatchTasks).size()), left);
}

// SIGTERM drains a worker that holds a batch: it finishes the task in hand, gives the ones it has not started back
// (attempts `released`, no failure counted), delivers what it finished and exits at once; another worker renders
// the rest, every task is merged once, and the image equals the embedded render up to rounding. `rendering` is the
// worker's log line of a task of the batch's kind.
void expectDrainGivesBackTheRestOfABatch(Farm &farm, int res, const std::string &spec, const std::string &rendering) {
    const std::string scene = writeTestScene(farm.dir() + "/scene", res, 8);
    farm.startMaster();
    const std::string ref = farm.embeddedRender(scene, spec, "ref");
    Process &worker = farm.startWorker(1, {"--batch", "16"});
    const auto [code, output] = farm.cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    ASSERT_TRUE(waitUntil([&] { return worker.log().find(rendering) != std::string::npos; }, 60s)) << worker.log();
    worker.signal(SIGTERM);
    const auto exitCode = worker.wait(60s);
    ASSERT_TRUE(exitCode) << worker.log();
    EXPECT_EQ(*exitCode, 0) << worker.log();
    const std::string ofJob = " AND job_id = " + std::to_string(id);
    EXPECT_GT(farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'released'" + ofJob), 0) << worker.log();
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state IN ('failed', 'expired')" + ofJob), 0)
        << worker.log();
    EXPECT_GE(farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'completed'" + ofJob), 1) << worker.log();
    farm.startWorker(2);
    v1::Job job;
    expectDoneAsEmbedded(farm, id, ref, job);
}

TEST_F(FarmTest, ADrainingWorkerGivesBackTheUnstartedChainTasksOfItsBatch) {
    // 4 rounds of 3 chain tasks of about 34000 mutations each (a few tenths of a second).
    expectDrainGivesBackTheRestOfABatch(*farm, 64,
                                        "--integrator erpt --spp 4 --seed 6 -P maxDepth=4 -P luminanceSamples=2000 "
                                        "-P directSamples=0 -P passMutations=400000",
                                        "rendering chain task");
}

TEST_F(FarmTest, ADrainingWorkerGivesBackTheUnstartedImageTasksOfItsBatch) {
    expectDrainGivesBackTheRestOfABatch(*farm, 128, "--spp 256 --seed 6", "rendering samples");
}

// A batch of chain tasks accepted ahead of its turn waits on disk through a master restart, is merged once as
// the tasks it names, and the image equals the embedded render up to the batch's rounding.
TEST_F(FarmTest, AChainBatchWaitingForItsTurnSurvivesAMasterRestart) {
    farm->startMaster(kFastLeases);
    std::string scene, ref;
    int64_t id = -1;
    // Enough chain tasks that the batcher's share of those not yet issued (with `first` live) holds three.
    ASSERT_NO_FATAL_FAILURE(submitBesideEmbedded(
        *farm, "--integrator mlt --spp 256 -P luminanceSamples=5000 -P directSamples=0", scene, ref, id));
    FakeWorker first(*farm), batcher(*farm);
    std::optional<ChainPayloads> payloads;
    // The seeding, then the first chain task (no direct component), which `first` keeps.
    std::vector<v1::TaskSpec> head;
    ASSERT_NO_FATAL_FAILURE(seedAndLeaseNext(first, scene, payloads, head));
    ASSERT_TRUE(head[0].has_chain());
    const std::vector<v1::TaskSpec> batch = batcher.leaseBatch(3);
    ASSERT_EQ(batch.size(), 3u);
    for (size_t i = 0; i < batch.size(); ++i) {
        EXPECT_TRUE(batch[i].has_chain());
        EXPECT_EQ(batch[i].task_index(), head[0].task_index() + 1 + static_cast<int64_t>(i));
    }
    EXPECT_TRUE(
        batcher.complete(batch[0].attempt_id(), payloads->payload(batch), grpc::StatusCode::OK, laterAttempts(batch))
            .accepted());
    farm->killMaster();
    farm->startMaster(kFastLeases);
    EXPECT_TRUE(first.complete(head[0].attempt_id(), payloads->payload(head)).accepted());
    v1::Job job;
    ASSERT_NO_FATAL_FAILURE(finishChainJob(*farm, first, *payloads, id, 2, ref, job));
    // The batch was merged from its file, not lost and rendered again: one attempt per task.
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM attempts WHERE job_id = " + std::to_string(id)),
              job.tasks().total());
}

// A chain job batches its chain tasks only: a result that names a direct-component task and the chain task after
// it as one batch is refused as a bad request, and nothing of it is stored; each alone is taken.
TEST_F(FarmTest, ABatchOfADirectAndAChainTaskIsRefused) {
    std::string scene;
    int64_t id = -1;
    ASSERT_NO_FATAL_FAILURE(
        submitOnNewMaster(*farm, "--integrator mlt --spp 64 -P luminanceSamples=5000 -P directSamples=1", scene, id));
    FakeWorker w(*farm);
    std::optional<ChainPayloads> payloads;
    std::vector<v1::TaskSpec> direct;
    ASSERT_NO_FATAL_FAILURE(seedAndLeaseNext(w, scene, payloads, direct));
    ASSERT_TRUE(direct[0].has_image());
    // The pass's direct task comes first, then its chain task; leased one by one, then claimed as a batch.
    const std::vector<v1::TaskSpec> chain = w.leaseBatch(1);
    ASSERT_EQ(chain.size(), 1u);
    ASSERT_TRUE(chain[0].has_chain());
    ASSERT_EQ(chain[0].task_index(), direct[0].task_index() + 1);
    const int64_t results = farm->queryStore("SELECT COUNT(*) FROM results");
    w.complete(direct[0].attempt_id(), payloads->payload(direct), grpc::StatusCode::INVALID_ARGUMENT,
               {chain[0].attempt_id()});
    EXPECT_NE(w.lastError().find("is not chain task"), std::string::npos) << w.lastError();
    EXPECT_EQ(farm->queryStore("SELECT COUNT(*) FROM results"), results);
    EXPECT_TRUE(w.complete(direct[0].attempt_id(), payloads->payload(direct)).accepted());
    EXPECT_TRUE(w.complete(chain[0].attempt_id(), payloads->payload(chain)).accepted());
}

}  // namespace
}  // namespace pf::test::farm
