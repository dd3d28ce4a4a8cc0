// Storage faults on the master, with real processes and real files damaged on disk (issue 18, item 3):
// result files and checkpoints that are truncated, flipped or gone are rendered again rather than failing
// the job or merging wrong bits (tasks are reproducible); a damaged SQLite store and an unwritable data
// directory are refused at start with a clear error, and the master resumes once the fault is cleared; a
// full data directory (a small tmpfs) stalls the job without losing or failing anything until there is
// room again. Every job ends with the bits of its embedded render and each task merged exactly once.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/mount.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "farm/harness.h"

namespace pf::test::farm {
namespace {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

// At 128 x 128 with --spp 160: 16 tasks of 8 spp, then 2 of 16 (render/image_task.h).
constexpr int kTasks = 18;
const std::string kSpec = "--spp 160 --seed 21";

std::string slurp(const std::string &path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

void spill(const std::string &path, const std::string &data) {
    std::ofstream(path, std::ios::binary | std::ios::trunc) << data;
}

// One byte in the middle of the file, inverted: what a bad sector or a stray write leaves.
void flipByte(const std::string &path) {
    std::string data = slurp(path);
    ASSERT_GT(data.size(), 2u) << path;
    data[data.size() / 2] = static_cast<char>(~data[data.size() / 2]);
    spill(path, data);
}

// The film files (*.blk) of `dir` whose names start with `prefix`, sorted.
std::vector<std::string> filesIn(const std::string &dir, const std::string &prefix) {
    std::vector<std::string> out;
    for (const auto &e : fs::directory_iterator(dir))
        if (e.path().filename().string().rfind(prefix, 0) == 0 && e.path().extension() == ".blk")
            out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
    return out;
}

// A master that must refuse to start: its exit code and log.
std::pair<int, std::string> refusedMaster(const Farm &farm, const std::string &data) {
    Process master({PATHFARM_MASTER_BIN, "--listen", farm.address(), "--data", data, "--token-file",
                    farm.clientTokenFile(), "--worker-token-file", farm.workerTokenFile()},
                   farm.dir() + "/refused-" + std::to_string(freePort()) + ".log");
    const auto code = master.wait(30s);
    return {code ? *code : -999, master.log()};
}

class StorageFaults : public FarmTest {
protected:
    // Renders the reference, starts a master with `args` and two workers, submits the job and, once
    // `ready` holds, kills the workers and then the master: the store and files stay as they were.
    void runUntil(const std::vector<std::string> &args, const std::function<bool()> &ready) {
        scene = writeTestScene(farm->dir() + "/scene", res, 8);
        reference = farm->embeddedRender(scene, spec, "reference");
        farm->startMaster(args);
        Process &a = farm->startWorker(1);
        Process &b = farm->startWorker(1);
        const auto [code, output] = farm->cli("submit " + scene + " " + spec);
        ASSERT_EQ(code, 0) << output;
        id = jobIdFrom(output);
        ASSERT_TRUE(waitUntil(ready, 180s)) << farm->master().log();
        a.signal(SIGKILL);
        b.signal(SIGKILL);
        farm->killMaster();
        ASSERT_NE(count("SELECT state FROM jobs WHERE id = "), v1::JOB_DONE) << "the job ended too early";
    }

    int64_t count(const std::string &sql) const { return farm->queryStore(sql + std::to_string(id)); }
    std::string jobDir() const { return farm->dir() + "/data/jobs/" + std::to_string(id); }

    // A master (with `args`) and two workers again, and the job's end as expectExactImage wants it.
    void resume(const std::vector<std::string> &args) {
        farm->startMaster(args);
        farm->startWorker(1);
        farm->startWorker(1);
        expectExactImage();
    }

    // The job finishes with the reference's bits, every task merged exactly once.
    void expectExactImage() {
        const v1::Job done = farm->waitForJob(id, 240s);
        ASSERT_EQ(done.state(), v1::JOB_DONE) << done.DebugString() << farm->master().log();
        const std::string out = farm->dir() + "/farm.exr";
        const auto [code, fetched] = farm->cli("fetch " + std::to_string(id) + " -o " + out);
        ASSERT_EQ(code, 0) << fetched;
        EXPECT_TRUE(sameBits(reference, out));
        const int64_t tasks = count("SELECT COUNT(*) FROM tasks WHERE job_id = ");
        EXPECT_EQ(count("SELECT COUNT(*) FROM merges WHERE job_id = "), tasks);
        EXPECT_EQ(count("SELECT COUNT(DISTINCT task_idx) FROM merges WHERE job_id = "), tasks);
    }

    std::string spec = kSpec, scene, reference;
    int res = 128;
    int64_t id = -1;
};

TEST_F(StorageFaults, DamagedOrMissingResultFilesAreRenderedAgain) {
    // No checkpoint before the end: accepted results wait in their files.
    const std::vector<std::string> args = {"--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "3600000"};
    runUntil(args, [&] { return count("SELECT COUNT(*) FROM results WHERE job_id = ") >= 5; });
    const std::vector<std::string> results = filesIn(jobDir() + "/results", "");
    ASSERT_GE(results.size(), 5u);
    flipByte(results[0]);
    fs::resize_file(results[1], fs::file_size(results[1]) / 2);
    fs::remove(results[2]);
    spill(results[3], "");

    resume(args);
    const std::string log = farm->master().log();
    EXPECT_NE(log.find("fails its checksum"), std::string::npos) << log;
    EXPECT_NE(log.find("rendering the task again"), std::string::npos) << log;
    EXPECT_NE(log.find("is truncated"), std::string::npos) << log;
    EXPECT_NE(log.find("cannot read"), std::string::npos) << log;
    // Four tasks completed twice: once into the lost files, once more after the restart.
    EXPECT_EQ(count("SELECT COUNT(*) FROM attempts WHERE state = 'completed' AND job_id = "), kTasks + 4);
}

TEST_F(StorageFaults, DamagedCheckpointIsRenderedAgain) {
    const std::vector<std::string> args = {"--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "200"};
    runUntil(args, [&] { return count("SELECT COUNT(*) FROM merges WHERE job_id = ") >= 4; });
    // One checkpoint, or two if the master was killed between writing one and removing the last.
    const std::vector<std::string> checkpoints = filesIn(jobDir(), "checkpoint-");
    ASSERT_GE(checkpoints.size(), 1u);
    for (const std::string &c : checkpoints) flipByte(c);

    resume(args);
    const std::string log = farm->master().log();
    EXPECT_NE(log.find("cannot be restored"), std::string::npos) << log;
    EXPECT_NE(log.find("fails its checksum"), std::string::npos) << log;
}

// A Markov-chain job keeps its seeding results for its lifetime: the chains and b̂ depend on them, so one
// that is damaged makes the restarted master render the whole job again, seeding first.
TEST_F(StorageFaults, DamagedSeedingOfAChainJobIsRenderedAgain) {
    // At 80 x 80: 16 seeding tasks, four direct-component tasks, then chain tasks (test_farm_chains).
    res = 80;
    spec = "--integrator pssmlt --spp 64 -P luminanceSamples=20000 -P directSamples=4 --seed 7 -P maxDepth=4";
    const std::vector<std::string> args = {"--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "200"};
    runUntil(args, [&] { return count("SELECT COUNT(*) FROM merges WHERE job_id = ") >= 3; });
    const std::vector<std::string> seeding = filesIn(jobDir() + "/results", "0-");
    ASSERT_EQ(seeding.size(), 1u);
    flipByte(seeding[0]);

    resume(args);
    const std::string log = farm->master().log();
    EXPECT_NE(log.find("cannot be restored"), std::string::npos) << log;
    EXPECT_NE(log.find("fails its checksum"), std::string::npos) << log;
}

// Damage in the SQLite file itself: first its header, then (the header restored) a page of its tables.
TEST_F(StorageFaults, DamagedStoreIsRefusedAndTheRestoredOneResumes) {
    const std::vector<std::string> args = {"--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "200"};
    runUntil(args, [&] { return count("SELECT COUNT(*) FROM merges WHERE job_id = ") >= 2; });
    const std::string store = farm->storePath();
    {  // Everything into the main file, so that its pages hold the tables.
        sqlite3 *db = nullptr;
        ASSERT_EQ(sqlite3_open(store.c_str(), &db), SQLITE_OK);
        ASSERT_EQ(sqlite3_exec(db, "PRAGMA wal_checkpoint(TRUNCATE)", nullptr, nullptr, nullptr), SQLITE_OK);
        sqlite3_close(db);
    }
    const std::string backup = slurp(store);
    ASSERT_GT(backup.size(), 4 * 4096u);

    std::string damaged = backup;
    damaged.replace(0, 16, "not a database!!");
    spill(store, damaged);
    auto [code, log] = refusedMaster(*farm, farm->dir() + "/data");
    EXPECT_EQ(code, 1) << log;
    EXPECT_NE(log.find("store.sqlite is damaged"), std::string::npos) << log;
    EXPECT_NE(log.find("file is not a database"), std::string::npos) << log;

    damaged = backup;
    for (size_t i = 2 * 4096; i < 3 * 4096; ++i) damaged[i] = static_cast<char>(i * 131);
    spill(store, damaged);
    std::tie(code, log) = refusedMaster(*farm, farm->dir() + "/data");
    EXPECT_EQ(code, 1) << log;
    EXPECT_NE(log.find("store.sqlite is damaged"), std::string::npos) << log;

    spill(store, backup);
    resume(args);
    EXPECT_NE(farm->master().log().find("resumed"), std::string::npos) << farm->master().log();
}

// Mounts a tmpfs of `bytes` at `dir` (root only); unmounts it when the scope ends.
class Tmpfs {
public:
    Tmpfs(const std::string &dir, size_t bytes) : dir_(dir) {
        fs::create_directories(dir);
        mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, ("size=" + std::to_string(bytes)).c_str()) == 0;
        if (!mounted_) error_ = std::string("cannot mount a tmpfs: ") + std::strerror(errno);
    }
    ~Tmpfs() {
        if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
    }
    Tmpfs(const Tmpfs &) = delete;
    Tmpfs &operator=(const Tmpfs &) = delete;
    const std::string &error() const { return error_; }
    bool remount(unsigned long flags) {
        return ::mount("tmpfs", dir_.c_str(), "tmpfs", MS_REMOUNT | flags, nullptr) == 0;
    }

private:
    std::string dir_, error_;
    bool mounted_ = false;
};

// The data directory is a tmpfs mounted over the farm's: read-only (root writes through any permission
// bits), then full.
TEST_F(StorageFaults, UnwritableDataDirectoryIsRefusedAtStart) {
    const std::string data = farm->dir() + "/data";
    Tmpfs disk(data, 64 << 20);
    if (!disk.error().empty()) GTEST_SKIP() << disk.error() << " (needs root)";
    ASSERT_TRUE(disk.remount(MS_RDONLY));
    const auto [code, log] = refusedMaster(*farm, data);
    EXPECT_EQ(code, 1) << log;
    EXPECT_NE(log.find("data directory is not writable"), std::string::npos) << log;
    EXPECT_NE(log.find("Read-only file system"), std::string::npos) << log;

    ASSERT_TRUE(disk.remount(0));
    farm->startMaster();
    EXPECT_TRUE(farm->master().running());
}

TEST_F(StorageFaults, FullDataDirectoryStallsTheJobUntilThereIsRoom) {
    const std::string data = farm->dir() + "/data";
    Tmpfs disk(data, 16 << 20);
    if (!disk.error().empty()) GTEST_SKIP() << disk.error() << " (needs root)";
    scene = writeTestScene(farm->dir() + "/scene", 128, 8);
    reference = farm->embeddedRender(scene, kSpec, "reference");
    farm->startMaster({"--lease-ms", "1500", "--heartbeat-ms", "250", "--checkpoint-ms", "200"});
    farm->startWorker(1);
    farm->startWorker(1);
    const auto [code, output] = farm->cli("submit " + scene + " " + kSpec);
    ASSERT_EQ(code, 0) << output;
    id = jobIdFrom(output);
    ASSERT_TRUE(waitUntil([&] { return count("SELECT COUNT(*) FROM merges WHERE job_id = ") >= 2; }, 180s))
        << farm->master().log();

    // Fill the disk to the last block.
    const std::string filler = data + "/filler";
    {
        std::ofstream out(filler, std::ios::binary);
        const std::string block(1 << 16, 'x');
        while (out.write(block.data(), static_cast<std::streamsize>(block.size()))) {
        }
    }
    ASSERT_TRUE(
        waitUntil([&] { return farm->master().log().find("No space left on device") != std::string::npos; }, 120s))
        << farm->master().log();
    // Stalled, not failed, for a while: workers keep their leases and retry their uploads.
    std::this_thread::sleep_for(3s);
    const auto stub = farm->clientStub();
    v1::GetJobRequest req;
    req.set_id(id);
    v1::Job job;
    ASSERT_TRUE(stub->GetJob(farm->context(farm->clientToken()).get(), req, &job).ok());
    EXPECT_EQ(job.state(), v1::JOB_RUNNING) << job.DebugString();
    EXPECT_LT(job.tasks().merged(), kTasks);
    EXPECT_TRUE(farm->master().running());

    fs::remove(filler);
    expectExactImage();
}

}  // namespace
}  // namespace pf::test::farm
