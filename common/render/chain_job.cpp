#include "render/chain_job.h"

#include <stdexcept>

#include "scene/scene.h"

namespace pf {

namespace {

constexpr uint64_t kDirectSeedTag = 0xd12ec7ULL;

}  // namespace

uint64_t directComponentSeed(uint64_t jobSeed) { return hashCombine(jobSeed, kDirectSeedTag); }

ChainJob::ChainJob(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed, int64_t spp)
    : scene_(scene),
      integrator_(integrator),
      seed_(seed),
      spp_(spp),
      config_(integrator.seeding(scene, spp)),
      seedingTasks_(seedingTasks(scene)),
      direct_(makeFilmBlock(scene)),
      chains_(makeFilmBlock(scene)) {
    // The direct component is rendered by its own integrator in the image tasks `render` would run for it.
    if (integrator.directIntegrator() && integrator.directSamples() > 0)
        for (int64_t first = 0; first < integrator.directSamples();
             first += imageTaskSize(integrator.directSamples(), first))
            directTasks_.push_back({first, imageTaskSize(integrator.directSamples(), first)});
}

ChainJob::Phase ChainJob::phaseOf(uint64_t task) const {
    return task < seedingTaskCount() ? Phase::Seeding : task < firstChainTask() ? Phase::Direct : Phase::Chain;
}

uint64_t ChainJob::chainTaskCount() const {
    if (!seeded()) throw std::logic_error("chain tasks before the seeding is merged");
    if (!(normalizer_->luminance() > 0)) return 0;
    return spp_ > 0 ? integrator_.chainTaskCount(scene_, spp_) : UINT64_MAX;
}

ChainTask ChainJob::chainTask(uint64_t task) const {
    if (!seeded() || task < firstChainTask()) throw std::logic_error("no chain task " + std::to_string(task));
    return integrator_.chainTask(scene_, *normalizer_, seed_, spp_, task - firstChainTask());
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
    Bitmap image = developChains(film, chains_, integrator_.chainKind(), seeded() ? normalizer_->luminance() : 0.0);
    if (directSpp_ > 0) {
        // As the direct integrator's own render develops it (render_loop.cpp), then added.
        const Bitmap direct = film.develop(direct_, 1.0 / static_cast<double>(directSpp_));
        for (size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] += direct.rgb[i];
    }
    return image;
}

}  // namespace pf
