#include "render/chain_job.h"

#include <algorithm>
#include <stdexcept>

#include "scene/scene.h"

namespace pf {

namespace {

constexpr uint64_t kDirectSeedTag = 0xd12ec7ULL;

}  // namespace

ImageTaskResult runDirectTask(const Scene &scene, const ChainIntegrator &integrator, uint64_t jobSeed,
                              const ImageTask &task, int threads) {
    const SamplingIntegrator *direct = integrator.directIntegrator();
    if (!direct) throw std::logic_error("a direct task of an integrator without a direct component");
    constexpr SampleSequence kStratified{true, 0};
    return runImageTask(scene, *direct, hashCombine(jobSeed, kDirectSeedTag), task, threads, &kStratified);
}

ChainJob::ChainJob(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, int64_t spp)
    : scene_(scene),
      integrator_(integrator),
      seed_(seed),
      spp_(spp),
      config_(integrator.seeding(scene, spp)),
      seedingTasks_(integrator.seedingTasks(scene)),
      direct_(makeFilmBlock(scene)),
      chains_(makeFilmBlock(scene)) {
    if (integrator.directIntegrator() && integrator.directSamples() > 0) directSamples_ = integrator.directSamples();
    const Film &film = scene.sensor().film();
    const uint64_t pixels = static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight());
    directChunk_ =
        std::clamp<int64_t>(static_cast<int64_t>(pixels / kDirectChunkPixels), 1, std::max<int64_t>(1, directSamples_));
    // The pace of the direct component: its samples spread over the passes of the budget, or of the budget a
    // time budget's passes are planned for.
    const int64_t paceSpp = spp > 0 ? spp : integrator.timeBudgetPlan(scene);
    pacePasses_ =
        std::max<uint64_t>(1, integrator.chainTaskCount(scene, paceSpp) / integrator.tasksPerPass(scene, paceSpp));
}

uint64_t ChainJob::passCount() const {
    if (!seeded()) throw std::logic_error("chain tasks before the seeding is merged");
    if (!(normalizer_->luminance() > 0)) return 0;
    return spp_ > 0 ? integrator_.chainTaskCount(scene_, spp_) / tasksPerPass() : UINT64_MAX;
}

uint64_t ChainJob::directBefore(uint64_t pass) const {
    const uint64_t d = static_cast<uint64_t>(directSamples_);
    if (d == 0) return 0;
    if (spp_ > 0 && pass >= passCount()) return directTasks(d);
    const uint64_t paced = ((pass + 1) * d + pacePasses_ - 1) / pacePasses_;
    return directTasks(spp_ > 0 ? std::min(d, paced) : paced);
}

uint64_t ChainJob::directSize(uint64_t task) const {
    const auto c = static_cast<uint64_t>(directChunk_);
    return task == 0 ? 1 : std::min(c, uint64_t(1) << std::min<uint64_t>(task - 1, 62));
}

uint64_t ChainJob::directStart(uint64_t task) const {
    uint64_t start = 0;
    for (uint64_t k = 0; k < task; ++k) {
        const uint64_t size = directSize(k);
        if (size == static_cast<uint64_t>(directChunk_)) return start + (task - k) * size;  // whole chunks from k on
        start += size;
    }
    return start;
}

uint64_t ChainJob::directTasks(uint64_t samples) const {
    uint64_t start = 0, k = 0;
    for (; start < samples; ++k) {
        const uint64_t size = directSize(k);
        if (size == static_cast<uint64_t>(directChunk_)) return k + (samples - start + size - 1) / size;
        start += size;
    }
    return k;
}

uint64_t ChainJob::taskCount() const {
    const uint64_t passes = passCount();
    if (passes == UINT64_MAX) return UINT64_MAX;
    return firstChainTask() + passes * tasksPerPass() + directTaskCount();
}

ChainJob::Slot ChainJob::locate(uint64_t task) const {
    if (!seeded() || task < firstChainTask() || task >= taskCount())
        throw std::logic_error("no chain-phase task " + std::to_string(task));
    const uint64_t j = task - firstChainTask(), perPass = tasksPerPass(), passes = passCount();
    // The unit of pass k (its direct tasks, then its chain tasks) starts at k * perPass + directBefore(k - 1),
    // which grows with k: the last k whose unit starts at or before j. With a finite budget, k = passes is
    // the unit of the direct tasks left after the last pass.
    const auto unitStart = [&](uint64_t k) { return k * perPass + (k > 0 ? directBefore(k - 1) : 0); };
    uint64_t lo = 0, hi = passes == UINT64_MAX ? j / perPass + 1 : passes;
    while (lo < hi) {
        const uint64_t mid = lo + (hi - lo + 1) / 2;
        if (unitStart(mid) <= j)
            lo = mid;
        else
            hi = mid - 1;
    }
    const uint64_t k = lo, firstChain = k * perPass + directBefore(k);
    if (j < firstChain) return {Phase::Direct, j - k * perPass, k};
    return {Phase::Chain, j - directBefore(k), k};
}

ChainJob::Phase ChainJob::phaseOf(uint64_t task) const {
    return task < firstChainTask() ? Phase::Seeding : locate(task).phase;
}

ImageTask ChainJob::directTask(uint64_t task) const {
    const Slot s = locate(task);
    if (s.phase != Phase::Direct) throw std::logic_error("task " + std::to_string(task) + " is no direct task");
    // A budget in samples ends with the samples left; a time budget's direct component has no end.
    const auto first = static_cast<int64_t>(directStart(s.ordinal)), size = static_cast<int64_t>(directSize(s.ordinal));
    return {first, spp_ > 0 ? std::min(size, directSamples_ - first) : size};
}

ChainTask ChainJob::chainTask(uint64_t task) const {
    const Slot s = locate(task);
    if (s.phase != Phase::Chain) throw std::logic_error("task " + std::to_string(task) + " is no chain task");
    return integrator_.chainTask(scene_, *normalizer_, seed_, spp_, s.ordinal);
}

bool ChainJob::startsPass(uint64_t task) const {
    const Slot s = locate(task);
    const uint64_t j = task - firstChainTask(), perPass = tasksPerPass();
    return j == s.pass * perPass + (s.pass > 0 ? directBefore(s.pass - 1) : 0);
}

void ChainJob::mergeSeeding(SeedingResult result) {
    if (seeded()) throw std::logic_error("seeding merged twice");
    seeding_.push_back(std::move(result));
    if (seeding_.size() == seedingTaskCount()) {
        normalizer_.emplace(std::move(seeding_));
        seeding_.clear();
    }
}

void ChainJob::mergeDirect(const ImageBlock &block, int64_t samplesPerPixel) {
    direct_.merge(block);
    directSpp_ += samplesPerPixel;
}

void ChainJob::restore(ImageBlock direct, int64_t directSamplesPerPixel, ChainImage chains) {
    direct_ = std::move(direct);
    directSpp_ = directSamplesPerPixel;
    chains_ = std::move(chains);
}

int64_t ChainJob::mutationsPerPixel() const {
    const Film &film = scene_.sensor().film();
    return static_cast<int64_t>(chains_.mutations /
                                (static_cast<uint64_t>(film.cropWidth()) * static_cast<uint64_t>(film.cropHeight())));
}

Bitmap ChainJob::develop() const {
    const Film &film = scene_.sensor().film();
    Bitmap image = developChains(
        film, chains_, integrator_.chainImageScale(scene_, spp_, chains_, seeded() ? normalizer_->luminance() : 0.0));
    if (directSpp_ > 0) {
        // As the direct integrator's own render develops it (render_loop.cpp), then added.
        const Bitmap direct = film.develop(direct_, 1.0 / static_cast<double>(directSpp_));
        for (size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] += direct.rgb[i];
    }
    return image;
}

}  // namespace pf
