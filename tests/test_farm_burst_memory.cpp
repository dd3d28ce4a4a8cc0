// Bounded memory of burst jobs at real image sizes (render/burst.h): a 1024 x 1024 mept job at one seed
// sample per pixel stays below a stated peak resident size in the embedded renderer, the master and a
// worker. The last round's design pooled every seed of the image before the first burst (12 GB and growing
// at 1024² with 64 seeds per pixel); passes of (pass, block) tasks hold only the tasks in flight, whose films
// keep only the tiles their chains deposited in (image/splat_tiles.h), beside the job's merged films of 7
// doubles per pixel (59 MB each at 1024²). Peak sizes are read from the kernel (getrusage for the embedded
// render, VmHWM for the farm's processes), never timed.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <fstream>

#include "farm/harness.h"
#include "image/bitmap.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

// A process's peak resident size in MiB, from /proc.
double peakMiB(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/status");
    for (std::string line; std::getline(in, line);)
        if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
    ADD_FAILURE() << "no VmHWM for process " << pid;
    return 0;
}

// The bounds, about 1.5 times the peaks measured when this test was written (embedded 310 MiB with 2 threads,
// master 521 MiB, worker 386 MiB with 2 threads, when every task's film covered the whole crop window; with
// tiled films 148, 384 and 58 MiB): the films in flight, the scene and the process. They do not grow with
// the passes; the seed pool of the last round's design alone took about 40 bytes per candidate, several per
// pixel and seed sample.
constexpr double kEmbeddedBoundMiB = 480, kMasterBoundMiB = 800, kWorkerBoundMiB = 600;

class FarmBurstMemory : public FarmTest {};

TEST_F(FarmBurstMemory, A1024SquaredMeptJobStaysBelowItsBounds) {
    const std::string scene = writeTestScene(farm->dir() + "/scene", 1024, 1);
    // One round of one seed sample per pixel; few, short bursts, so that the seeding of a million pixels
    // and the films dominate, as they do at any budget.
    const std::string spec =
        "--integrator mept --spp 1 --seed 3 -P maxDepth=3 -P directSamples=-1 -P chainLength=20 -P numChains=0.2";
    const std::string ref = farm->embeddedRender(scene, spec + " --threads 2", "embedded");
    rusage usage{};
    ASSERT_EQ(getrusage(RUSAGE_CHILDREN, &usage), 0);
    const double embedded = static_cast<double>(usage.ru_maxrss) / 1024.0;

    Process &master = farm->startMaster();
    Process &worker = farm->startWorker(2);
    const std::string out = farm->dir() + "/farm.exr";
    const auto [code, output] = farm->cli("submit " + scene + " " + spec + " --wait -o " + out);
    ASSERT_EQ(code, 0) << output << farm->master().log();
    EXPECT_TRUE(sameBits(ref, out));
    const double masterPeak = peakMiB(master.pid()), workerPeak = peakMiB(worker.pid());
    std::printf("1024^2 mept, one seed sample per pixel: peak resident size embedded %.0f MiB, master %.0f MiB, "
                "worker (2 threads) %.0f MiB\n",
                embedded, masterPeak, workerPeak);
    EXPECT_LT(embedded, kEmbeddedBoundMiB);
    EXPECT_LT(masterPeak, kMasterBoundMiB);
    EXPECT_LT(workerPeak, kWorkerBoundMiB);
}

}  // namespace
}  // namespace pf::test::farm
