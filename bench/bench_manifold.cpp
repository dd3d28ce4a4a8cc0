// Manifold exploration ([TR §8]; ALGORITHMS.md §5.4-5.5, §8.3) on the TORUS scene and veach-bidir: the
// statistics of Table 1 for MEPT and MEMLT, chain throughput per core, and the error at equal time of MEPT,
// MEMLT, ERPT and BDPT against a long BDPT reference.
//
//   bench_manifold [--res N] [--time S] [--runs K] [--first-run F] [--threads N] [--seed-spp N] [--mpp N] [--lambda
//   L|auto]
//                  [--chain-length M] [--methods bdpt,memlt,erpt,mept,mept-nomedia,mept-nodistance] [--table1 0|1]
//                  [--references DIR]
//                  [--glossy-angle D] (manifoldGlossyAngle of mept and memlt in degrees, default 1)
//                  [--ref-spp N]
//                  [--out DIR] [scene.xml ...]
//   bench_manifold --sweep-lambda L1,.. [--sweep-length M1,..] [--sweep-seeds N1,..] [same options] [scene ...]
//   bench_manifold --bursts K [same options] [scene.xml ...]   (what one burst does; 5. below)
//   bench_manifold --write-references K [--ref-spp N] [--res N] [--threads N] [--references DIR] [scene.xml ...]
//
// 1. Table 1, per core (one thread, seeding excluded from the time): `mept` with seed-spp seeds per pixel
//    (default 32) and about 100 mutations per pixel in bursts of chain-length (default 1000), and `memlt`
//    with mpp mutations per pixel (default 32), both at lambda L (default 50; TORUS's row of Table 1 says
//    100; tune it with --sweep-lambda, acceptance moves with the walk's code): mutations, acceptance,
//    manifold walks per mutation, walks converged, mean Newton iterations, mean and largest specular chain,
//    reverse walks and non-reversible proposals, mutations per CPU second.
// 2. Equal time at N x N (default 32): K runs (default 3, seeds 7 + F, 8 + F, ...; F splits the runs between
//    processes, e.g. one per core of a bigger machine, whose summaries are then averaged by hand) per method on
//    `threads` threads (default 1), each with a budget fitted to S CPU seconds per thread (default 8). CPU time, not
//    wall time, because this machine is shared (wall time would charge a method for the other processes), and a fitted
//    budget, not a clock, because erpt and mept bursts have none: a burst is never cut, and a second pass over the
//    seeds would count their energy twice (README "Status"). The budget is bdpt's samples per pixel, memlt's mutations
//    per pixel, or the bursts per pixel (numChains) of erpt and mept at seed-spp seeds per pixel (default 32, TORUS's
//    row of Table 8.1) and chain-length mutations per burst; probe renders fit CPU time = fixed cost + cost per unit x
//    budget. Each method's mean wall and CPU time are printed, and relMSE x CPU time / (S x threads) next to relMSE,
//    which corrects what remains of a miss for an unbiased method (its error falls as 1 / time). relMSE is the mean
//    over pixels and channels of (x - r)^2 / (r^2 + 1e-2) against the reference r, also without the 0.1% worst pixels
//    ("trim"); the reference's own relMSE (from the spread of its runs) is printed with it: a run's expected relMSE is
//    its own plus the reference's.
// 3. --sweep-lambda: the equal-time runs of `mept` alone for every seeds per pixel, chain length and lambda
//    given, with acceptance and the walk statistics (the seeds tune lambda in 50-500 for 72-78% acceptance).
// 4. --write-references K: the reference of each scene, the mean of K independent BDPT renders with
//    ref-spp samples per pixel each (seeds 1000, 1001, ...), written to DIR/<scene directory>-<N>.exr
//    (default DIR bench/references) with its own relMSE estimated from the spread of the K renders
//    (variance of the mean per pixel and channel over (mean^2 + 1e-2)). Without a reference file the
//    equal-time part renders one with ref-spp samples per pixel (default 2048) and says so.
// 5. --bursts K: per burst method, bursts per pixel, energy and pixels covered per burst, CPU time per burst and
//    acceptance per mutation type (burstStudy).
// --out writes the reference and each method's last image as EXR. Figures only, never pass/fail.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench_support.h"
#include "image/bitmap.h"
#include "integrators/integrator.h"
#include "render/chain.h"
#include "render/image_task.h"
#include "render/normalizer.h"
#include "scene/scene.h"

namespace {

namespace fs = std::filesystem;

constexpr double kEpsilon = 1e-2;  // relMSE's epsilon, as bench::relativeError
constexpr uint64_t kReferenceSeed = 1000, kRunSeed = 7, kProbeSeed = 99;
constexpr int kProbeSeeds = 3;  // seeds per probe point of the budget fit (budgetForTime)

struct Options {
    int res = 32, refSpp = 2048, seedSpp = 32, mpp = 32, runs = 3, firstRun = 0, writeReferences = 0;
    bool table1 = true;
    int threads = 1;
    int64_t chainLength = 1000;
    double seconds = 8, lambda = 50, glossyAngle = 1, bursts = 0;
    std::vector<double> sweepLambdas;
    std::vector<int64_t> sweepLengths, sweepSeeds;
    std::vector<std::string> scenes, methods = {"bdpt", "memlt", "erpt", "mept"};
    std::string references = "bench/references", out;
};

// What a method is run with besides the scene's maxDepth: the manifold perturbation's lambda; for bursts
// their length and mean count per pixel; spp: the budget (bdpt samples, memlt mutations or burst seeds per
// pixel).
struct Params {
    double lambda = 100, numChains = 1;
    int64_t chainLength = 100, spp = 0;
    double glossyAngle = 1;  // manifoldGlossyAngle of mept and memlt, in degrees
};

// "mept-nomedia" is mept without medium vertices in its chains (mediumChains = false), for the media scenes;
// "mept-nodistance" mept without the medium-distance perturbation (mediumDistancePerturbation = false).
bool isBurst(const std::string &type) { return type == "erpt" || type.starts_with("mept"); }

std::unique_ptr<pf::Integrator> integrator(const pf::Scene &scene, const std::string &method, const Params &p) {
    const std::string type = method.starts_with("mept-") ? "mept" : method;
    pf::Properties props(pf::ObjectKind::Integrator, type, {});
    if (method == "mept-nomedia") props.set("mediumChains", pf::Properties::Type::Boolean, false, {});
    if (method == "mept-nodistance") props.set("mediumDistancePerturbation", pf::Properties::Type::Boolean, false, {});
    const pf::Properties &file = scene.integratorProperties();
    if (file.has("maxDepth")) props.set("maxDepth", pf::Properties::Type::Integer, file.getInt("maxDepth"), {});
    // lambda 0: "auto" (the pilot tunes it; mept only, memlt keeps its default).
    if (type == "mept" && !(p.lambda > 0)) props.set("lambda", pf::Properties::Type::String, std::string("auto"), {});
    if ((type == "mept" || type == "memlt") && p.lambda > 0)
        props.set("lambda", pf::Properties::Type::Float, p.lambda, {});
    if (type == "mept" || type == "memlt")
        props.set("manifoldGlossyAngle", pf::Properties::Type::Float, p.glossyAngle, {});
    if (isBurst(type)) {
        props.set("chainLength", pf::Properties::Type::Integer, p.chainLength, {});
        props.set("numChains", pf::Properties::Type::Float, p.numChains, {});
    }
    return pf::createIntegrator(type, props, true);
}

template <typename T>
std::vector<T> parseList(const char *text, T (*parse)(const std::string &)) {
    std::vector<T> values;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');) values.push_back(parse(item));
    return values;
}

double percent(uint64_t part, uint64_t whole) { return whole ? 100.0 * static_cast<double>(part) / whole : 0.0; }

uint64_t sumProposed(const pf::MutationCounts &counts, bool accepted) {
    uint64_t n = 0;
    for (const pf::MutationCount &c : counts) n += accepted ? c.accepted : c.proposed;
    return n;
}

// ---------------------------------------------------------------------------------------------------------
// Table 1

// Seeding, then the chain tasks one after the other on this thread; ChainImage::seconds becomes the chain
// tasks' CPU time (not their wall time, which counts other processes on a shared machine), so seeding stays
// out of the throughput.
pf::ChainImage chainsOnOneCore(const pf::Scene &scene, const pf::ChainIntegrator &chains, int64_t spp) {
    std::vector<pf::SeedingResult> seeding;
    for (const pf::SeedingTask &task : chains.seedingTasks(scene))
        seeding.push_back(chains.runSeeding(scene, 0, 1, task));
    const pf::Normalizer normalizer(std::move(seeding));
    pf::ChainImage image(pf::makeFilmBlock(scene));
    const std::clock_t cpu = std::clock();
    for (uint64_t k = 0; k < chains.chainTaskCount(scene, spp); ++k)
        pf::mergeChainResult(image, pf::runChainTask(scene, chains, 1, chains.chainTask(scene, normalizer, 1, spp, k)));
    image.seconds = static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC;
    return image;
}

// Table 1's walk columns from a chain's counters: walks per mutation, converged %, mean Newton iterations,
// mean and largest specular chain, reverse walks and non-reversible %, and the medium vertices that proposals
// walked in chains per walk (§6.7), and the converged walks whose chain crosses an index-matched boundary (%).
std::string walkColumns(pf::ChainCounters counters, uint64_t proposed) {
    const auto value = [&](const char *name) { return pf::counter(counters, name).value; };
    const double walks = value("manifoldWalks"), reverse = value("manifoldReverseWalks");
    const double perWalk = walks > 0 ? 1 / walks : 0;
    const double converged = value("manifoldWalksConverged");
    char line[200];
    std::snprintf(line, sizeof line, "%10.0f %7.2f %8.1f%% %7.2f %6.2f %4.0f %9.0f %6.2f%% %6.2f %6.2f%%", walks,
                  proposed ? walks / static_cast<double>(proposed) : 0.0, 100 * converged * perWalk,
                  value("manifoldNewtonIterations") * perWalk, value("manifoldChainVertices") * perWalk,
                  value("manifoldChainVerticesMax"), reverse,
                  reverse > 0 ? 100 * value("manifoldNonReversible") / reverse : 0.0,
                  value("manifoldMediumVertices") * perWalk,
                  converged > 0 ? 100 * value("manifoldCrossingWalks") / converged : 0.0);
    return line;
}
const char *const kWalkHeader = "     walks walks/m converged  Newton   size  max   reverse  nonrev  media  cross";

void printTable1(const std::string &label, const pf::ChainImage &image) {
    const uint64_t proposed = sumProposed(image.counts, false), accepted = sumProposed(image.counts, true);
    std::printf("%-7s %11llu %8.1f%% %s %11.4g\n", label.c_str(), static_cast<unsigned long long>(proposed),
                percent(accepted, proposed), walkColumns(image.counters, proposed).c_str(),
                image.seconds > 0 ? static_cast<double>(image.mutations) / image.seconds : 0.0);
    for (const pf::MutationCount &c : image.counts)
        if (c.proposed > 0)
            std::printf("        %-14s %llu proposed, %.1f%% accepted\n", c.name.c_str(),
                        static_cast<unsigned long long>(c.proposed), percent(c.accepted, c.proposed));
}

void table1(const Options &o, const pf::Scene &scene) {
    std::printf("%-7s %11s %9s %s %11s\n", "method", "mutations", "accepted", kWalkHeader, "mutations/s");
    // MEPT: about 100 mutations per pixel, as bursts of chainLength.
    const Params p{o.lambda, 100.0 / static_cast<double>(o.chainLength), o.chainLength, 0, o.glossyAngle};
    for (const std::string type : {"mept", "memlt"}) {
        const auto method = integrator(scene, type, p);
        printTable1(type, chainsOnOneCore(scene, dynamic_cast<const pf::ChainIntegrator &>(*method),
                                          type == "mept" ? o.seedSpp : o.mpp));
    }
}

// ---------------------------------------------------------------------------------------------------------
// References

fs::path referencePath(const Options &o, const std::string &scenePath) {
    return fs::path(o.references) /
           (fs::path(scenePath).parent_path().filename().string() + "-" + std::to_string(o.res) + ".exr");
}

// The mean of the K = writeReferences independent BDPT renders so far and the relMSE of that mean, estimated
// per pixel and channel as the variance of the mean (sample variance / K) over (mean^2 + epsilon).
pf::Bitmap referenceMean(const Options &o, const std::string &path, const std::vector<double> &sum,
                         const std::vector<double> &squares, int runs, double seconds, double &selfError) {
    pf::Bitmap mean(o.res, o.res);
    selfError = 0;
    for (size_t i = 0; i < sum.size(); ++i) {
        const double m = sum[i] / runs, variance = runs > 1 ? (squares[i] - runs * m * m) / (runs - 1) : 0.0;
        mean.rgb[i] = static_cast<float>(m);
        selfError += std::max(variance, 0.0) / runs / (m * m + kEpsilon);
    }
    selfError /= static_cast<double>(sum.size());
    mean.metadata = {{"pathfarm.integrator", "bdpt"},
                     {"pathfarm.scene", path},
                     {"pathfarm.spp", std::to_string(static_cast<int64_t>(runs) * o.refSpp)},
                     {"pathfarm.referenceRuns", std::to_string(runs) + " x " + std::to_string(o.refSpp) +
                                                    " spp, seeds " + std::to_string(kReferenceSeed) + ".." +
                                                    std::to_string(kReferenceSeed + runs - 1)},
                     {"pathfarm.referenceRelMSE", std::to_string(selfError)},
                     {"pathfarm.renderSeconds", std::to_string(seconds)}};
    return mean;
}

// Renders the runs one after the other and rewrites the reference after each from the second on, so that
// a stopped run leaves the mean of those done (its metadata says how many).
void writeReference(const Options &o, const std::string &path) {
    const auto scene = bench::loadWithSampleCount(path, o.refSpp, o.res, "bench_manifold");
    const auto bdpt = integrator(*scene, "bdpt", {});
    const fs::path file = referencePath(o, path);
    fs::create_directories(file.parent_path());
    std::vector<double> sum, squares;
    double seconds = 0, selfError = 0;
    for (int k = 0; k < o.writeReferences; ++k) {
        pf::RenderStats stats;
        const pf::Bitmap image = bench::renderWith(*scene, *bdpt, o.refSpp, 0, kReferenceSeed + k, o.threads, stats);
        sum.resize(image.rgb.size()), squares.resize(image.rgb.size());
        for (size_t i = 0; i < image.rgb.size(); ++i)
            sum[i] += image.rgb[i], squares[i] += double(image.rgb[i]) * image.rgb[i];
        seconds += stats.seconds;
        if (k > 0) pf::writeEXR(file.string(), referenceMean(o, path, sum, squares, k + 1, seconds, selfError));
        std::printf("  %s: run %d/%d, %d spp, seed %llu, %.1f s; mean's own relMSE %.3g\n", path.c_str(), k + 1,
                    o.writeReferences, o.refSpp, static_cast<unsigned long long>(kReferenceSeed + k), stats.seconds,
                    selfError);
        std::fflush(stdout);
    }
    std::printf("%s: %d x %d spp in %.0f s -> %s; its own relMSE %.3g (one run's %.3g)\n", path.c_str(),
                o.writeReferences, o.refSpp, seconds, file.string().c_str(), selfError, selfError * o.writeReferences);
}

struct Reference {
    pf::Bitmap image;
    double selfError = 0;  // its own relMSE, 0 when unknown
};

Reference loadReference(const Options &o, const std::string &path, const pf::Scene &scene) {
    const fs::path file = referencePath(o, path);
    Reference ref;
    if (fs::exists(file)) {
        ref.image = pf::readEXR(file.string());
        if (ref.image.width != o.res || ref.image.height != o.res)
            throw std::runtime_error(file.string() + ": reference is not " + std::to_string(o.res) + " x " +
                                     std::to_string(o.res));
        const auto self = ref.image.metadata.find("pathfarm.referenceRelMSE");
        if (self != ref.image.metadata.end()) ref.selfError = std::stod(self->second);
        std::printf("reference: %s (bdpt %s spp), its own relMSE %.3g\n", file.string().c_str(),
                    ref.image.metadata["pathfarm.spp"].c_str(), ref.selfError);
        return ref;
    }
    pf::RenderStats stats;
    ref.image = bench::renderWith(scene, *integrator(scene, "bdpt", {}), o.refSpp, 0, kReferenceSeed, o.threads, stats);
    std::printf("reference: none at %s, rendered bdpt %d spp in %.1f s (own error unknown)\n", file.string().c_str(),
                o.refSpp, stats.seconds);
    return ref;
}

// ---------------------------------------------------------------------------------------------------------
// Equal time

struct Run {
    double seconds = 0, cpuSeconds = 0;  // wall time, and the process's CPU time over every thread
    uint64_t samples = 0;                // mutations for chains, pixel samples for bdpt
    pf::MutationCounts counts;
    pf::ChainCounters counters;
    bench::RelativeError error;
    pf::Bitmap image;
};

Run runOnce(const Options &o, const pf::Scene &scene, const std::string &type, const Params &p, uint64_t seed,
            const Reference &ref) {
    pf::RenderStats stats;
    Run run;
    const std::clock_t cpu = std::clock();
    run.image = bench::renderWith(scene, *integrator(scene, type, p), p.spp, 0, seed, o.threads, stats);
    run.seconds = stats.seconds;
    run.cpuSeconds = static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC;
    run.samples = stats.samples;
    run.counts = stats.counts;
    run.counters = stats.counters;
    if (!ref.image.rgb.empty()) run.error = bench::relativeError(run.image, ref.image);
    return run;
}

// The budget for o.seconds of CPU time per thread: CPU time = a + b x knob, fitted through probe renders
// (their seed differs from the runs'), where the knob is bdpt's samples or memlt's mutations per pixel, or
// the bursts per pixel of erpt and mept (at p.spp seeds per pixel). CPU time rather than wall time,
// because the machine may be shared: wall time would charge a method for what other processes ran.
Params budgetForTime(const Options &o, const pf::Scene &scene, const std::string &type, Params p) {
    const bool bursts = isBurst(type);
    const auto set = [&](double knob) {
        if (bursts)
            p.numChains = std::max(0.01, knob);
        else
            p.spp = std::max<int64_t>(1, std::llround(knob));
    };
    const double budget = o.seconds * o.threads, k1 = bursts ? 0.25 : 16;
    // A burst render's cost at a given numChains depends on its seed: the bursts launched are numChains times
    // the seeds' luminance over the pilot's W, both heavy-tailed on the egg (glass-egg at 64², numChains 0.5:
    // 50-56 mutations per pixel for seeds 7-10, 67 for the probe seed 99; with that one probe seed mept was
    // fitted 19 of its 30 CPU s). Each probe point is therefore the mean over kProbeSeeds seeds.
    // CPU seconds summed over the probe renders of seeds kProbeSeed + [from, from + count).
    const auto cpuSum = [&](int from, int count) {
        double sum = 0;
        for (int k = from; k < from + count; ++k) sum += runOnce(o, scene, type, p, kProbeSeed + k, {}).cpuSeconds;
        return sum;
    };
    set(k1);
    // The first render of a method is slower (caches, first-touch allocations): a warm-up, not a probe.
    runOnce(o, scene, type, p, kProbeSeed, {});
    const double t1 = cpuSum(0, kProbeSeeds) / kProbeSeeds;
    // The second probe grows until it takes a quarter of the budget: closer to t1, the slope is noise when
    // a fixed cost dominates (memlt's seeding). The growth steps take one seed, the last point all of them.
    double k2 = k1, t2 = t1;
    for (int step = 0; step < 8 && (step == 0 || t2 < budget / 4); ++step) {
        k2 *= 4;
        set(k2);
        t2 = cpuSum(0, 1);
    }
    t2 = (t2 + cpuSum(1, kProbeSeeds - 1)) / kProbeSeeds;
    const double perKnob = t2 > t1 ? (t2 - t1) / (k2 - k1) : t2 / k2, fixed = std::max(0.0, t1 - perKnob * k1);
    set((budget - fixed) / perKnob);
    return p;
}

struct Summary {
    double seconds = 0, cpuSeconds = 0, relMse = 0, relMseSd = 0, trimmed = 0, normalized = 0, perCore = 0,
           acceptance = 0;
    uint64_t proposed = 0;
    pf::ChainCounters counters;
};

// K runs with seeds kRunSeed + firstRun + k: mean and standard deviation over runs.
Summary equalTime(const Options &o, const pf::Scene &scene, const std::string &type, const Params &p,
                  const Reference &ref, pf::Bitmap *last) {
    Summary s;
    std::vector<double> errors;
    uint64_t accepted = 0;
    for (int k = 0; k < o.runs; ++k) {
        Run run = runOnce(o, scene, type, p, kRunSeed + o.firstRun + k, ref);
        errors.push_back(run.error.all);
        s.seconds += run.seconds / o.runs;
        s.trimmed += run.error.trimmed / o.runs;
        s.cpuSeconds += run.cpuSeconds / o.runs;
        s.normalized += run.error.all * run.cpuSeconds / (o.seconds * o.threads) / o.runs;
        s.perCore += static_cast<double>(run.samples) / run.cpuSeconds / o.runs;
        s.proposed += sumProposed(run.counts, false), accepted += sumProposed(run.counts, true);
        pf::addCounters(s.counters, run.counters);
        if (last) *last = std::move(run.image);
    }
    for (double e : errors) s.relMse += e / o.runs;
    for (double e : errors) s.relMseSd += (e - s.relMse) * (e - s.relMse);
    s.relMseSd = o.runs > 1 ? std::sqrt(s.relMseSd / (o.runs - 1)) : 0.0;
    s.acceptance = percent(accepted, s.proposed);
    return s;
}

// Wall and CPU seconds, samples per CPU second, acceptance, relMSE with its standard deviation over runs,
// trimmed relMSE, and relMSE scaled to S CPU seconds per thread (for an unbiased method the error falls as
// 1 / time, so this corrects for an overshoot or for CPU lost to other processes on a shared machine).
std::string summaryColumns(const Summary &s) {
    char line[160];
    std::snprintf(line, sizeof line, "%7.2f %7.2f %11.4g %7.1f%% %9.4g %8.2g %9.4g %9.4g", s.seconds, s.cpuSeconds,
                  s.perCore, s.acceptance, s.relMse, s.relMseSd, s.trimmed, s.normalized);
    return line;
}
const char *const kSummaryHeader = "   wall     cpu   samples/s  accept    relMSE       sd      trim   at S cpu";

void equalTimeTable(const Options &o, const std::string &path, const pf::Scene &scene, const Reference &ref) {
    std::printf("equal time: %g CPU s per thread, %d runs, %d threads; bursts: %d seeds/px, length %lld, lambda %g\n",
                o.seconds, o.runs, o.threads, o.seedSpp, static_cast<long long>(o.chainLength), o.lambda);
    std::printf("method %s\n", kSummaryHeader);
    const std::string stem = o.out.empty() ? "" : o.out + "/" + fs::path(path).parent_path().filename().string();
    if (!stem.empty()) pf::writeEXR(stem + "-reference.exr", ref.image);
    for (const std::string &type : o.methods) {
        const Params p =
            budgetForTime(o, scene, type, {o.lambda, 1, o.chainLength, isBurst(type) ? o.seedSpp : 0, o.glossyAngle});
        pf::Bitmap image;
        const Summary s = equalTime(o, scene, type, p, ref, &image);
        std::printf("%-7s %s\n", type.c_str(), summaryColumns(s).c_str());
        if (isBurst(type))
            std::printf("        (%.3g bursts/px)\n", p.numChains);
        else
            std::printf("        (%lld %s/px)\n", static_cast<long long>(p.spp),
                        type == "bdpt" ? "samples" : "mutations");
        std::fflush(stdout);
        if (!stem.empty()) pf::writeEXR(stem + "-" + type + ".exr", image);
    }
    std::printf(
        "(reference's own relMSE %.3g is part of every relMSE above; samples/s: mutations, or bdpt's "
        "pixel samples, per CPU second, seeding included)\n",
        ref.selfError);
}

void lambdaSweep(const Options &o, const pf::Scene &scene, const Reference &ref) {
    std::printf("mept sweep: %g CPU s per thread, %d runs, %d threads\n", o.seconds, o.runs, o.threads);
    std::printf(" seeds lambda length bursts/px %s %s\n", kSummaryHeader, kWalkHeader);
    const auto orDefault = [](const std::vector<int64_t> &list, int64_t value) {
        return list.empty() ? std::vector<int64_t>{value} : list;
    };
    for (const int64_t seeds : orDefault(o.sweepSeeds, o.seedSpp))
        for (const int64_t length : orDefault(o.sweepLengths, o.chainLength))
            for (const double lambda : o.sweepLambdas) {
                const Params p = budgetForTime(o, scene, "mept", {lambda, 1, length, seeds, o.glossyAngle});
                const Summary s = equalTime(o, scene, "mept", p, ref, nullptr);
                std::printf("%6lld %6g %6lld %9.3g %s %s\n", static_cast<long long>(seeds), lambda,
                            static_cast<long long>(length), p.numChains, summaryColumns(s).c_str(),
                            walkColumns(s.counters, s.proposed).c_str());
                std::fflush(stdout);
            }
}

// --bursts K: what one burst does, for each burst method at K bursts per pixel (seed-spp seeds, bursts of
// chain-length, lambda L), one thread: bursts per pixel, the mean energy of a burst (luminance of its
// deposits, in units of the mean pixel luminance W), the pixels it covers (the participation ratio
// (sum e)^2 / sum e^2 of its per-pixel energies e: the number of equally lit pixels it amounts to), CPU
// seconds per burst and the acceptance of each mutation type.
void burstStudy(const Options &o, const pf::Scene &scene) {
    std::printf("bursts (one thread; %g bursts/px, %d seeds/px, length %lld, lambda %g)\n", o.bursts, o.seedSpp,
                static_cast<long long>(o.chainLength), o.lambda);
    std::printf("method  bursts/px  energy/W  pixels/burst (sd)  CPU ms/burst\n");
    for (const std::string &type : o.methods) {
        if (!isBurst(type)) continue;
        const auto method = integrator(scene, type, {o.lambda, o.bursts, o.chainLength, o.seedSpp, o.glossyAngle});
        const auto &chains = dynamic_cast<const pf::ChainIntegrator &>(*method);
        std::vector<pf::SeedingResult> seeding;
        for (const pf::SeedingTask &task : chains.seedingTasks(scene))
            seeding.push_back(chains.runSeeding(scene, 0, 1, task));
        const pf::Normalizer normalizer(std::move(seeding));
        pf::ImageBlock film = pf::makeFilmBlock(scene);
        pf::MutationCounts counts = chains.mutationTypes();
        pf::ChainCounters counters;
        pf::PCG32 rng;
        double bursts = 0, energy = 0, spread = 0, spread2 = 0;
        const std::clock_t cpu = std::clock();
        for (uint64_t k = 0; k < chains.chainTaskCount(scene, o.seedSpp); ++k) {
            const pf::ChainTask task = chains.chainTask(scene, normalizer, 1, o.seedSpp, k);
            uint64_t samples = 0;
            for (const pf::ChainSeed &seed : chains.taskSeeds(scene, 1, task, samples)) {
                film.clear();
                chains.runChain(scene, 1, task, seed, pf::chainDepositScale(chains.chainKind(), seed, task.mutations),
                                rng, film, counts, counters);
                double sum = 0, squares = 0;
                const std::span<const double> splat = film.splatData();
                for (size_t i = 0; i + 2 < splat.size(); i += 3) {
                    const double e = (splat[i] + splat[i + 1] + splat[i + 2]) / 3;
                    sum += e, squares += e * e;
                }
                const double pixels = squares > 0 ? sum * sum / squares : 0;
                bursts += 1, energy += sum, spread += pixels, spread2 += pixels * pixels;
            }
        }
        const double seconds = static_cast<double>(std::clock() - cpu) / CLOCKS_PER_SEC;
        const double pixels = static_cast<double>(scene.sensor().film().cropWidth()) *
                              static_cast<double>(scene.sensor().film().cropHeight());
        const double meanSpread = spread / std::max(1.0, bursts);
        std::printf("%-7s %9.3f %9.3g %8.2f (%6.2f) %12.3g\n", type.c_str(), bursts / pixels,
                    energy / std::max(1.0, bursts) / (normalizer.luminance() / pixels), meanSpread,
                    std::sqrt(std::max(0.0, spread2 / std::max(1.0, bursts) - meanSpread * meanSpread)),
                    1000 * seconds / std::max(1.0, bursts));
        for (const pf::MutationCount &c : counts)
            if (c.proposed > 0)
                std::printf("        %-14s %llu proposed, %.1f%% accepted\n", c.name.c_str(),
                            static_cast<unsigned long long>(c.proposed), percent(c.accepted, c.proposed));
        std::fflush(stdout);
    }
}

void benchScene(const Options &o, const std::string &path) {
    std::printf("\n== %s, %d x %d\n", path.c_str(), o.res, o.res);
    const auto scene = bench::loadWithSampleCount(path, o.seedSpp, o.res, "bench_manifold");
    const Reference ref = loadReference(o, path, *scene);
    if (!o.sweepLambdas.empty()) return lambdaSweep(o, *scene, ref);
    if (o.bursts > 0) return burstStudy(o, *scene);
    if (o.table1) {
        std::printf(
            "Table 1 (one thread; mept: %d seeds/px, 100 mutations/px in bursts of %lld; memlt: %d mutations/px; "
            "lambda %g)\n",
            o.seedSpp, static_cast<long long>(o.chainLength), o.mpp, o.lambda);
        table1(o, *scene);
    }
    equalTimeTable(o, path, *scene, ref);
}

}  // namespace

int main(int argc, char **argv) {
    Options o;
    const auto toDouble = [](const std::string &s) { return std::stod(s); };
    const auto toString = [](const std::string &s) { return s; };
    const auto toInt = [](const std::string &s) { return static_cast<int64_t>(std::stoll(s)); };
    const std::map<std::string, std::function<void(const char *)>> flags = {
        {"--res", [&](const char *v) { o.res = std::stoi(v); }},
        {"--time", [&](const char *v) { o.seconds = std::stod(v); }},
        {"--runs", [&](const char *v) { o.runs = std::stoi(v); }},
        {"--first-run", [&](const char *v) { o.firstRun = std::stoi(v); }},
        {"--ref-spp", [&](const char *v) { o.refSpp = std::stoi(v); }},
        {"--seed-spp", [&](const char *v) { o.seedSpp = std::stoi(v); }},
        {"--mpp", [&](const char *v) { o.mpp = std::stoi(v); }},
        {"--lambda", [&](const char *v) { o.lambda = std::string(v) == "auto" ? 0.0 : std::stod(v); }},
        {"--glossy-angle", [&](const char *v) { o.glossyAngle = std::stod(v); }},
        {"--chain-length", [&](const char *v) { o.chainLength = std::stoll(v); }},
        {"--sweep-lambda", [&](const char *v) { o.sweepLambdas = parseList<double>(v, +toDouble); }},
        {"--sweep-length", [&](const char *v) { o.sweepLengths = parseList<int64_t>(v, +toInt); }},
        {"--sweep-seeds", [&](const char *v) { o.sweepSeeds = parseList<int64_t>(v, +toInt); }},
        {"--write-references", [&](const char *v) { o.writeReferences = std::stoi(v); }},
        {"--references", [&](const char *v) { o.references = v; }},
        {"--methods", [&](const char *v) { o.methods = parseList<std::string>(v, +toString); }},
        {"--bursts", [&](const char *v) { o.bursts = std::stod(v); }},
        {"--table1", [&](const char *v) { o.table1 = std::stoi(v) != 0; }},
        {"--threads", [&](const char *v) { o.threads = std::stoi(v); }},
        {"--out", [&](const char *v) { o.out = v; }}};
    try {
        for (int i = 1; i < argc; ++i) {
            const auto flag = flags.find(argv[i]);
            if (flag != flags.end() && i + 1 < argc)
                flag->second(argv[++i]);
            else if (std::string(argv[i]).starts_with("--"))
                throw std::runtime_error(std::string("unknown option or missing value: ") + argv[i]);
            else
                o.scenes.push_back(argv[i]);
        }
        if (o.firstRun < 0) throw std::runtime_error("--first-run must not be negative");
        if (o.res < 1 || o.runs < 1 || o.threads < 1 || o.seconds <= 0 || o.seedSpp < 1 || o.chainLength < 1 ||
            o.refSpp < 1)
            throw std::runtime_error(
                "--res, --runs, --threads, --time, --seed-spp, --chain-length, --ref-spp must be positive");
        if (o.writeReferences == 1 || o.writeReferences < 0)
            throw std::runtime_error("--write-references needs at least 2 runs (their spread is its error)");
        if (o.scenes.empty()) o.scenes = {"scenes/torus/scene.xml", "scenes/veach-bidir/scene.xml"};
        for (const std::string &path : o.scenes) {
            if (o.writeReferences > 0)
                writeReference(o, path);
            else
                benchScene(o, path);
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}
