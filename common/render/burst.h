// Burst rendering (ERPT, MEPT; ALGORITHMS.md §5.3) in passes over blocks of pixels, with no global seed
// pool: a task is (pass k, block b). It takes the BDPT seed samples of the block's pixels that pass k
// covers, launches their bursts at once and returns a film of unnormalized deposits (render/chain.h); the
// image is the sum of the films of P complete passes divided by P. Memory is that of the tasks in flight,
// whatever the resolution and the number of passes; the equal energy quanta come from the luminance pilot
// (render/pilot.h), not from the seeds.
//
// Passes and rounds. A round is one seed sample per pixel (Mitsuba's sampleCount counts rounds: `--spp N`
// is N rounds). A round launches pixels · chainsPerPixel · chainLength mutations on average (Mitsuba: numChains
// bursts per pixel over all its sampleCount seeds, so chainsPerPixel = numChains / rounds), 10^8 at 1024²
// with a single round and Mitsuba's defaults: far too much for one step of a time budget, which must consist
// of whole passes to stay unbiased. So a round is split into m = interleave passes of at most
// passMutations expected mutations (the integrator's parameter, 2^20 by default): pass k belongs to round r = k / m and
// covers the pixels i (crop-window index) with (i + o_r) mod m = k mod m, o_r uniform in [0, m) drawn from (job seed,
// r). Every pixel is covered once per round (sample index r), so m passes make exactly one round; and each pass on its
// own covers a pixel with probability 1/m, so its seeds carry weight m · w and the pass's film alone is an unbiased
// estimate of the image: any number of whole passes gives an unbiased image, which lets the clock stop a render after
// any pass.
#pragma once
#include <cstdint>
#include <vector>

#include "render/seeding.h"

namespace pf {

// Expected mutations of one pass by default: about 5 core-seconds of bursts at 2·10^5 mutations/s, a step
// of a time budget well below a minute on one machine. A pass is split into about kBlocksPerPass tasks, so
// that it spreads over a few workers' cores and a task's film is worth shipping.
constexpr int64_t kDefaultPassMutations = int64_t(1) << 20;
constexpr uint64_t kBlocksPerPass = 8;

struct BurstPlan {
    uint64_t pixels = 0;        // the crop window's
    double chainsPerPixel = 1;  // bursts per pixel and round, on average
    uint64_t interleave = 1;    // m: passes per round
    uint64_t blocks = 1;        // tasks per pass, equal ranges of crop-window pixels
    uint64_t tasksPerRound() const { return interleave * blocks; }
};

// The plan of a render whose seed samples launch `chainsPerPixel` bursts of `chainLength` mutations per
// pixel on average, in passes of at most `passMutations` expected mutations. A pure function of the scene
// and those parameters, so every machine agrees on it.
BurstPlan burstPlan(const Scene &scene, double chainsPerPixel, int64_t chainLength, int64_t passMutations);

// What a burst task is, beside its chain length: its pass and block, the pilot's W and the job's plan (so
// that a worker needs nothing of the job's budget).
struct BurstPass {
    uint64_t pass = 0, block = 0;
    double meanLuminance = 0;
    BurstPlan plan;
};

// The seed candidates of (pass, block): BDPT sample r = pass / m of each covered pixel of the block, every
// strategy of paths of at least config.minDepth edges, in pixel and strategy order, with weight the
// luminance of the MIS-weighted contribution of that one sample (config.samplesPerPixel is not used; the
// coverage factor m is the caller's).
// `samples` receives the BDPT samples taken.
std::vector<SeedCandidate> burstCandidates(const Scene &scene, const SeedingConfig &config, uint64_t seed,
                                           const BurstPass &task, uint64_t &samples);

}  // namespace pf
