#include "farm/chain_codec.h"

#include <cmath>

#include "core/math.h"
#include "farm/block_codec.h"
#include "farm/error.h"

namespace pf::farm {

namespace v1 = pathfarm::v1;

namespace {

void addRecord(v1::PathRecords &out, const PathRecord &r, double weight) {
    out.add_pixel(r.pixel);
    out.add_sample_index(r.sampleIndex);
    out.add_s(r.s);
    out.add_t(r.t);
    out.add_weight(weight);
}

// Calls fn(record, weight) for every record, after checking the columns.
template <class Fn>
void forEachRecord(const v1::PathRecords &in, const char *what, const Fn &fn) {
    const int n = in.pixel_size();
    if (in.sample_index_size() != n || in.s_size() != n || in.t_size() != n || in.weight_size() != n)
        throw FarmError(std::string(what) + ": path record columns of unequal length");
    for (int i = 0; i < n; ++i) {
        if (!std::isfinite(in.weight(i)) || in.weight(i) < 0 || in.s(i) < 0 || in.t(i) < 1)
            throw FarmError(std::string(what) + ": path record " + std::to_string(i) + " has a bad strategy or weight");
        fn(PathRecord{in.pixel(i), in.sample_index(i), in.s(i), in.t(i)}, in.weight(i));
    }
}

void encodeFirstStage(const FirstStageImage &image, v1::FirstStageImage &out) {
    out.set_reduction(static_cast<uint32_t>(image.reduction));
    out.set_width(static_cast<uint32_t>(image.width));
    out.set_height(static_cast<uint32_t>(image.height));
    for (const double l : image.luminance) out.add_luminance(l);
}

FirstStageImage decodeFirstStage(const v1::FirstStageImage &in, const char *what) {
    FirstStageImage out;
    if (in.reduction() == 0) return out;
    const uint64_t cells = static_cast<uint64_t>(in.width()) * in.height();
    if (in.reduction() > 1 << 16 || in.width() == 0 || in.height() == 0 || in.width() > 1 << 20 ||
        in.height() > 1 << 20 || static_cast<uint64_t>(in.luminance_size()) != cells)
        throw FarmError(std::string(what) + ": malformed first-stage image");
    for (const double l : in.luminance())
        if (!std::isfinite(l) || l < 0)
            throw FarmError(std::string(what) + ": a first-stage luminance is negative or not finite");
    out.reduction = static_cast<int>(in.reduction());
    out.width = static_cast<int>(in.width());
    out.height = static_cast<int>(in.height());
    out.luminance.assign(in.luminance().begin(), in.luminance().end());
    return out;
}

std::vector<double> finiteValues(const google::protobuf::RepeatedField<double> &in, const char *what) {
    for (const double v : in)
        if (!std::isfinite(v)) throw FarmError(std::string(what) + ": non-finite luminance");
    return {in.begin(), in.end()};
}

template <class Msg>
Msg parse(std::string_view payload, const char *what) {
    Msg msg;
    if (!msg.ParseFromArray(payload.data(), static_cast<int>(payload.size())))
        throw FarmError(std::string(what) + ": corrupt payload");
    return msg;
}

MutationCounts fromProto(const google::protobuf::RepeatedPtrField<v1::MutationCount> &in) {
    MutationCounts out;
    for (const v1::MutationCount &c : in) out.push_back({c.name(), c.proposed(), c.accepted()});
    return out;
}

ChainCounters fromProto(const google::protobuf::RepeatedPtrField<v1::ChainCounter> &in) {
    ChainCounters out;
    for (const v1::ChainCounter &c : in) {
        if (!std::isfinite(c.value())) throw FarmError("chain result: non-finite counter '" + c.name() + "'");
        out.push_back({c.name(), c.value(), c.maximum() ? ChainCounter::Merge::Max : ChainCounter::Merge::Sum});
    }
    return out;
}

template <class Figures>
v1::ChainOutput chainOutput(const Figures &r) {
    v1::ChainOutput out;
    out.set_film(encodeBlock(r.film));
    out.set_mutations(r.mutations);
    toProto(r.counts, *out.mutable_counts());
    toProto(r.counters, *out.mutable_counters());
    out.set_rays(r.rays);
    out.set_seconds(r.seconds);
    out.set_seed_samples(r.seedSamples);
    return out;
}

template <class Figures>
void readChainOutput(const v1::ChainOutput &in, Figures &r) {
    decodeBlock(in.film(), r.film);
    r.mutations = in.mutations();
    r.counts = fromProto(in.counts());
    r.counters = fromProto(in.counters());
    r.rays = in.rays();
    r.seconds = in.seconds();
    r.seedSamples = in.seed_samples();
}

// What the pilot tuned, as a task or a seeding result carries it (0: none): λ finite and not negative,
// dtheta an angle in [0, pi).
ManifoldTuning decodeTuning(double lambda, double mediumAngle, const char *what) {
    if (!std::isfinite(lambda) || lambda < 0) throw FarmError(std::string(what) + ": a bad jump size lambda");
    if (!(mediumAngle >= 0 && mediumAngle < kPi))
        throw FarmError(std::string(what) + ": a bad medium angle (dtheta) outside [0, pi)");
    return {lambda, mediumAngle};
}

}  // namespace

v1::ChainTask toProto(const ChainTask &task) {
    v1::ChainTask out;
    out.set_index(task.index);
    for (const ChainSeed &s : task.seeds) addRecord(*out.mutable_seeds(), s.record, s.weight);
    out.set_mutations(task.mutations);
    out.set_lambda(task.tuning.lambda);
    out.set_medium_angle(task.tuning.mediumAngle);
    for (const double l : task.depthLuminance) out.add_depth_luminance(l);
    if (task.firstStage.enabled()) encodeFirstStage(task.firstStage, *out.mutable_first_stage());
    if (task.burst) {
        v1::BurstPass *b = out.mutable_burst();
        b->set_pass(task.burst->pass);
        b->set_block(task.burst->block);
        b->set_mean_luminance(task.burst->meanLuminance);
        b->set_interleave(task.burst->plan.interleave);
        b->set_blocks(task.burst->plan.blocks);
        b->set_chains_per_pixel(task.burst->plan.chainsPerPixel);
    }
    return out;
}

ChainTask fromProto(const v1::ChainTask &task) {
    ChainTask out;
    out.index = task.index();
    forEachRecord(task.seeds(), "chain task", [&](const PathRecord &r, double weight) {
        out.seeds.push_back({r, weight});
    });
    out.mutations = task.mutations();
    out.depthLuminance = finiteValues(task.depth_luminance(), "chain task");
    out.tuning = decodeTuning(task.lambda(), task.medium_angle(), "chain task");
    out.firstStage = decodeFirstStage(task.first_stage(), "chain task");
    // The chains divide by it: every cell must be positive (the normalizer floors them).
    for (const double l : out.firstStage.luminance)
        if (!(l > 0)) throw FarmError("chain task: a first-stage luminance is not positive");
    if (task.has_burst()) {
        const v1::BurstPass &b = task.burst();
        if (!std::isfinite(b.mean_luminance()) || b.mean_luminance() < 0)
            throw FarmError("chain task: the burst pass's mean luminance is negative or not finite");
        if (b.interleave() < 1 || b.blocks() < 1 || b.block() >= b.blocks() || !std::isfinite(b.chains_per_pixel()) ||
            !(b.chains_per_pixel() > 0))
            throw FarmError("chain task: the burst pass's plan is malformed");
        BurstPlan plan;
        plan.interleave = b.interleave();
        plan.blocks = b.blocks();
        plan.chainsPerPixel = b.chains_per_pixel();
        out.burst = BurstPass{b.pass(), b.block(), b.mean_luminance(), plan};
    }
    return out;
}

void toProto(const SeedingTask &task, v1::SeedingTask &out) {
    out.set_first_pixel(task.firstPixel);
    out.set_pixel_count(task.pixelCount);
    out.set_pilot_samples(task.pilotSamples);
}

SeedingTask fromProto(const v1::SeedingTask &task) {
    return {task.first_pixel(), task.pixel_count(), task.pilot_samples()};
}

std::string encodeSeedingResult(const SeedingResult &result) {
    v1::SeedingOutput out;
    for (const SeedCandidate &c : result.candidates) {
        addRecord(*out.mutable_candidates(), c.record, c.weight);
        if (result.firstStage.enabled()) out.mutable_candidates()->add_cell(c.cell);
    }
    for (const double l : result.depthLuminance) out.add_depth_luminance(l);
    if (result.firstStage.enabled()) encodeFirstStage(result.firstStage, *out.mutable_first_stage());
    out.set_samples(result.samples);
    out.set_lambda(result.tuning.lambda);
    out.set_medium_angle(result.tuning.mediumAngle);
    out.set_rays(result.rays);
    out.set_seconds(result.seconds);
    return out.SerializeAsString();
}

SeedingResult decodeSeedingResult(std::string_view payload, const Film &film, const SeedingTask &task) {
    const auto in = parse<v1::SeedingOutput>(payload, "seeding result");
    SeedingResult out;
    // Candidates name the pixel whose sample generated them (light-tracing ones too), which must be one
    // of the task's, in order: the normalizer relies on the pool running in pixel order.
    const uint64_t width = static_cast<uint64_t>(film.width());
    uint64_t previous = task.firstPixel;
    out.firstStage = decodeFirstStage(in.first_stage(), "seeding result");
    if (out.firstStage.enabled()) {
        const FirstStageImage expected = FirstStageImage::zero(film, out.firstStage.reduction);
        if (out.firstStage.width != expected.width || out.firstStage.height != expected.height)
            throw FarmError("seeding result: the first-stage image does not cover the film");
    }
    const int cells = in.candidates().cell_size();
    if (cells != (out.firstStage.enabled() ? in.candidates().pixel_size() : 0))
        throw FarmError("seeding result: first-stage cells do not match the candidates");
    for (const uint32_t c : in.candidates().cell())
        if (c >= out.firstStage.luminance.size()) throw FarmError("seeding result: a first-stage cell out of range");
    forEachRecord(in.candidates(), "seeding result", [&](const PathRecord &r, double weight) {
        const int64_t x = static_cast<int64_t>(r.pixel % width) - film.cropX(),
                      y = static_cast<int64_t>(r.pixel / width) - film.cropY();
        const uint64_t crop =
            static_cast<uint64_t>(y) * static_cast<uint64_t>(film.cropWidth()) + static_cast<uint64_t>(x);
        if (x < 0 || y < 0 || x >= film.cropWidth() || y >= film.cropHeight() || crop < previous ||
            crop >= task.firstPixel + task.pixelCount)
            throw FarmError("seeding result: a candidate's pixel lies outside the task or out of order");
        previous = crop;
        const size_t i = out.candidates.size();
        out.candidates.push_back({r, weight, cells > 0 ? in.candidates().cell(static_cast<int>(i)) : 0u});
    });
    out.depthLuminance = finiteValues(in.depth_luminance(), "seeding result");
    out.tuning = decodeTuning(in.lambda(), in.medium_angle(), "seeding result");
    out.samples = in.samples();
    out.rays = in.rays();
    out.seconds = in.seconds();
    return out;
}

v1::ChainOutput toProto(const ChainImage &chains) {
    v1::ChainOutput out = chainOutput(chains);
    out.set_tasks(chains.tasks);
    return out;
}

std::string encodeChainResult(const ChainResult &result) { return chainOutput(result).SerializeAsString(); }

ChainResult decodeChainResult(std::string_view payload, ImageBlock film) {
    ChainResult out{std::move(film), 0, 0, {}, {}, 0, 0};
    readChainOutput(parse<v1::ChainOutput>(payload, "chain result"), out);
    return out;
}

ChainImage fromProto(const v1::ChainOutput &chains, ImageBlock film) {
    ChainImage out(std::move(film));
    readChainOutput(chains, out);
    out.tasks = chains.tasks();
    return out;
}

void toProto(const MutationCounts &counts, google::protobuf::RepeatedPtrField<v1::MutationCount> &out) {
    out.Clear();
    for (const MutationCount &c : counts) {
        v1::MutationCount *m = out.Add();
        m->set_name(c.name);
        m->set_proposed(c.proposed);
        m->set_accepted(c.accepted);
        m->set_acceptance(c.proposed > 0 ? static_cast<double>(c.accepted) / static_cast<double>(c.proposed) : 0.0);
    }
}

void toProto(const ChainCounters &counters, google::protobuf::RepeatedPtrField<v1::ChainCounter> &out) {
    out.Clear();
    for (const ChainCounter &c : counters) {
        v1::ChainCounter *m = out.Add();
        m->set_name(c.name);
        m->set_value(c.value);
        m->set_maximum(c.merge == ChainCounter::Merge::Max);
    }
}

}  // namespace pf::farm
