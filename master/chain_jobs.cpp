// Master: what a Markov-chain job (pssmlt, mmlt, mlt, erpt, ...) does differently from an image job.
// Its tasks are those of a render/chain_job.h ChainJob, in three phases: BDPT seeding tasks (candidate
// records and luminance sums, from which the master forms b̂ and the chains' starts), the direct
// component's image tasks, then chain tasks, formed once every seeding result is merged. The scheduler
// (scheduler.cpp) and the merger (merger.cpp) treat a chain job as a list of tasks and hand everything
// phase-specific to the functions here; what they keep is the gate of the chain phase (mayIssue issues
// tasks from chainFirst on only once `seeded`) and the decoding of payloads by task kind (decodeOutput).
// A new kind of chain-job task needs its TaskSpec in chainTaskWork, its payload's type in
// Master::TaskOutput and its decoding in decodeOutput, and its merge in mergeChainOutput.
#include <spdlog/spdlog.h>

#include <algorithm>

#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/error.h"
#include "film_files.h"
#include "runtime.h"

namespace pf::master {

namespace v1 = pathfarm::v1;

// ---------------------------------------------------------------------------------------------------
// Tasks and the film

v1::TaskSpec Master::chainTaskWork(const ChainJob &job, uint64_t index) {
    v1::TaskSpec work;
    switch (job.phaseOf(index)) {
        case ChainJob::Phase::Seeding:
            farm::toProto(job.seedingTask(index), *work.mutable_seeding());
            break;
        case ChainJob::Phase::Direct:
            work.mutable_image()->set_first_sample(job.directTask(index).firstSample);
            work.mutable_image()->set_sample_count(job.directTask(index).sampleCount);
            work.mutable_image()->set_direct(true);
            break;
        case ChainJob::Phase::Chain:
            *work.mutable_chain() = farm::toProto(job.chainTask(index));
            break;
    }
    return work;
}

void Master::openChainFilm(JobRuntime &j, Loaded loaded, const ChainIntegrator &integrator) {
    const JobSpec &spec = j.record.spec();
    auto state = std::make_unique<ChainState>();
    state->job = std::make_unique<ChainJob>(*loaded.scene, integrator, spec.seed(),
                                            spec.budget().has_spp() ? spec.budget().spp() : 0);
    state->loaded = std::move(loaded);
    const ChainJob &job = *state->job;
    j.chain = true;
    j.seedingTasks = static_cast<int64_t>(job.seedingTaskCount());
    j.chainFirst = static_cast<int64_t>(job.firstChainTask());
    j.seedingSpp = job.seedingConfig().samplesPerPixel;
    v1::ChainStats *stats = j.record.mutable_chain();
    if (stats->phase() == v1::CHAIN_PHASE_UNSPECIFIED) stats->set_phase(v1::CHAIN_PHASE_SEEDING);
    stats->set_seeding_tasks(job.seedingTaskCount());
    stats->set_direct_tasks(job.directTaskCount());
    stats->set_seeding_samples_per_pixel(j.seedingSpp);
    j.film.chain = std::move(state);
}

uint64_t Master::maxSeedingPayloadBytes(const JobRuntime &j, const v1::TaskSpec &work) {
    // Packed path records take at most 38 bytes (43 with a two-stage cell); a BDPT sample yields one
    // candidate per strategy. Two-stage MLT's first-stage image adds 8 bytes per cell.
    constexpr uint64_t kRecordBytes = 44, kMaxCandidatesPerSample = 256;
    const ChainJob &job = *j.film.chain->job;
    const int reduction = job.seedingConfig().firstStageReduction;
    const uint64_t cells =
        reduction > 0 ? FirstStageImage::zero(job.scene().sensor().film(), reduction).luminance.size() : 0;
    return work.seeding().pixel_count() * static_cast<uint64_t>(j.seedingSpp) * kMaxCandidatesPerSample * kRecordBytes +
           cells * 8 + (64 << 10);
}

bool Master::startsPass(const JobRuntime &j, int64_t index) {
    if (!j.chain || index < j.chainFirst || !j.seeded) return false;
    return j.film.chain->job->startsPass(static_cast<uint64_t>(index));
}

// ---------------------------------------------------------------------------------------------------
// Merging

void Master::mergeChainOutput(JobFilm &f, const v1::TaskSpec &work, TaskOutput output, int64_t tasks) {
    ChainJob &job = *f.chain->job;
    if (work.has_seeding()) {
        job.mergeSeeding(std::move(std::get<SeedingResult>(output)));
    } else if (work.has_chain()) {
        job.mergeChain(std::get<ChainResult>(output), static_cast<uint64_t>(tasks));
    } else {
        job.mergeDirect(std::get<ImageBlock>(output), work.image().sample_count());
    }
    f.spp = job.mutationsPerPixel();
}

void Master::recordChainMerge(JobRuntime &j, uint64_t seedingSamples, uint64_t directSamples) {
    const ChainJob &job = *j.film.chain->job;
    v1::ChainStats *stats = j.record.mutable_chain();
    const ChainImage &chains = job.chains();
    stats->set_mutations(chains.mutations);
    stats->set_mutations_per_pixel(job.mutationsPerPixel());
    stats->set_seeding_samples(stats->seeding_samples() + seedingSamples);
    stats->set_direct_samples(stats->direct_samples() + directSamples);
    stats->set_direct_samples_per_pixel(job.directSamplesPerPixel());
    stats->set_passes(job.passesMerged());
    stats->set_tasks_per_pass(job.tasksPerPass());
    farm::toProto(chains.counts, *stats->mutable_mutation_counts());
    farm::toProto(chains.counters, *stats->mutable_counters());
    if (job.seeded()) startChains(j);
}

void Master::startChains(JobRuntime &j) {
    if (j.seeded) return;
    const ChainJob &job = *j.film.chain->job;
    j.seeded = true;
    const uint64_t count = job.taskCount();
    if (j.total == 0 && count != UINT64_MAX) j.total = static_cast<int64_t>(count);
    v1::ChainStats *stats = j.record.mutable_chain();
    stats->set_phase(v1::CHAIN_PHASE_CHAINS);
    stats->set_luminance(job.normalizer().luminance());
    stats->set_lambda(job.normalizer().tuning().lambda);
    stats->set_medium_angle(job.normalizer().tuning().mediumAngle);
    stats->set_candidates(job.normalizer().candidates().size());
    spdlog::info("job={}: seeding merged: b = {:.6g} from {} candidates; {} chain and direct tasks", j.record.id(),
                 job.normalizer().luminance(), job.normalizer().candidates().size(),
                 count == UINT64_MAX ? std::string("time budget decides the")
                                     : std::to_string(count - static_cast<uint64_t>(j.chainFirst)));
    workChanged_.notify_all();
}

// ---------------------------------------------------------------------------------------------------
// Checkpoints and recovery

std::string Master::chainCheckpoint(const ChainJob &job) {
    v1::ChainCheckpoint cp;
    cp.set_direct(farm::encodeBlock(job.direct()));
    cp.set_direct_samples_per_pixel(job.directSamplesPerPixel());
    *cp.mutable_chains() = farm::toProto(job.chains());
    return cp.SerializeAsString();
}

void Master::restoreChainFilm(JobRuntime &j, const StoredJob &stored) {
    // The seeding results merged before the restart are merged again from their files, then the
    // checkpoint puts back the direct component and the chains.
    ChainJob &job = *j.film.chain->job;
    for (const StoredResult &r : store_.loadResults(j.record.id(), std::min(stored.mergedTasks, j.seedingTasks)))
        job.mergeSeeding(std::get<SeedingResult>(
            decodeOutput(j, chainTaskWork(job, static_cast<uint64_t>(r.taskIndex)), readFilmFile(r.file))));
    if (stored.checkpoint.empty()) return;
    v1::ChainCheckpoint cp;
    if (!cp.ParseFromString(readFilmFile(stored.checkpoint)))
        throw farm::FarmError("corrupt checkpoint " + stored.checkpoint);
    ImageBlock direct = makeFilmBlock(job.scene());
    farm::decodeBlock(cp.direct(), direct);
    job.restore(std::move(direct), cp.direct_samples_per_pixel(),
                farm::fromProto(cp.chains(), makeFilmBlock(job.scene())));
}

}  // namespace pf::master
