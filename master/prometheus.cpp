#include "prometheus.h"

#include <cstdio>
#include <map>
#include <sstream>
#include <utility>

#include "farm/convert.h"

namespace pf::master {

namespace v1 = pathfarm::v1;

namespace {

using Labels = std::vector<std::pair<std::string, std::string>>;

// One exposition: families (HELP and TYPE once) followed by their samples.
class Exposition {
public:
    void family(const std::string &name, const char *type, const char *help) {
        out_ << "# HELP " << name << ' ' << help << "\n# TYPE " << name << ' ' << type << '\n';
    }
    void sample(const std::string &name, const Labels &labels, double value) {
        out_ << name;
        if (!labels.empty()) {
            out_ << '{';
            for (size_t i = 0; i < labels.size(); ++i)
                out_ << (i ? "," : "") << labels[i].first << "=\"" << escaped(labels[i].second) << '"';
            out_ << '}';
        }
        char number[32];
        std::snprintf(number, sizeof number, "%.10g", value);
        out_ << ' ' << number << '\n';
    }
    std::string str() const { return out_.str(); }

private:
    // Label values escape backslash, double quote and line feed (the format's only escapes).
    static std::string escaped(const std::string &s) {
        std::string e;
        for (const char c : s) e += c == '\\' ? "\\\\" : c == '"' ? "\\\"" : c == '\n' ? "\\n" : std::string(1, c);
        return e;
    }
    std::ostringstream out_;
};

double perSecond(double amount, double seconds) { return seconds > 0 ? amount / seconds : 0; }

void farmWide(Exposition &e, const MasterMetrics &m, const std::vector<v1::Job> &jobs,
              const std::vector<v1::WorkerInfo> &workers) {
    e.family("pathfarm_jobs", "gauge", "Jobs the master holds, by state.");
    for (const auto &[state, n] : m.jobsByState) e.sample("pathfarm_jobs", {{"state", state}}, n);
    e.family("pathfarm_tasks", "gauge", "Tasks of the jobs the master holds, by state.");
    for (const auto &[state, n] : m.tasksByState) e.sample("pathfarm_tasks", {{"state", state}}, n);

    std::map<std::string, int> byState;
    for (const v1::WorkerState s : {v1::WORKER_IDLE, v1::WORKER_BUSY, v1::WORKER_DRAINING, v1::WORKER_LOST})
        byState[farm::stateName(s)] = 0;
    int threads = 0;
    for (const v1::WorkerInfo &w : workers) {
        ++byState[farm::stateName(w.state())];
        if (w.state() != v1::WORKER_LOST) threads += w.threads();
    }
    e.family("pathfarm_workers", "gauge", "Registered workers by state; lost ones missed their heartbeats.");
    for (const auto &[state, n] : byState) e.sample("pathfarm_workers", {{"state", state}}, n);
    e.family("pathfarm_worker_threads", "gauge", "Render threads of the workers that are not lost.");
    e.sample("pathfarm_worker_threads", {}, threads);

    e.family("pathfarm_samples_per_second", "gauge", "Pixel samples merged per second over the last minute.");
    e.sample("pathfarm_samples_per_second", {}, m.samplesPerSecond);
    double mutationsPerSecond = 0;
    for (const v1::Job &j : jobs)
        if (j.state() == v1::JOB_RUNNING && j.has_chain())
            mutationsPerSecond += perSecond(static_cast<double>(j.chain().mutations()), j.render_seconds());
    e.family("pathfarm_mutations_per_second", "gauge",
             "Mutations merged per second of rendering, summed over the running Markov-chain jobs.");
    e.sample("pathfarm_mutations_per_second", {}, mutationsPerSecond);
    e.family("pathfarm_samples_merged_total", "counter",
             "Pixel samples merged since the master started: image tasks, Markov-chain seeding and direct "
             "components (never mutations).");
    e.sample("pathfarm_samples_merged_total", {}, static_cast<double>(m.samplesMerged));
    e.family("pathfarm_mutations_merged_total", "counter", "Markov-chain mutations merged since the master started.");
    e.sample("pathfarm_mutations_merged_total", {}, static_cast<double>(m.mutationsMerged));

    e.family("pathfarm_merge_seconds", "summary", "Time spent decoding and merging task results, per result.");
    e.sample("pathfarm_merge_seconds_sum", {}, m.mergeSeconds);
    e.sample("pathfarm_merge_seconds_count", {}, static_cast<double>(m.resultsMerged));
    e.family("pathfarm_batch_tasks", "gauge",
             "Image tasks a worker with --batch auto leases at once now (grows while taking results keeps the "
             "master busy).");
    e.sample("pathfarm_batch_tasks", {}, m.batchTasks);
    e.family("pathfarm_result_bytes_total", "counter", "Bytes of accepted result payloads.");
    e.sample("pathfarm_result_bytes_total", {}, static_cast<double>(m.resultBytes));
    e.family("pathfarm_late_results_ignored_total", "counter", "Results of superseded attempts that were ignored.");
    e.sample("pathfarm_late_results_ignored_total", {}, static_cast<double>(m.lateResultsIgnored));
    e.family("pathfarm_results_lost_total", "counter",
             "Stored results that were unreadable or failed their checksum, and were rendered again.");
    e.sample("pathfarm_results_lost_total", {}, static_cast<double>(m.resultsLost));
    e.family("pathfarm_attempts_ended_total", "counter", "Attempts that ended without a result.");
    e.sample("pathfarm_attempts_ended_total", {{"reason", "expired"}}, static_cast<double>(m.attemptsExpired));
    e.sample("pathfarm_attempts_ended_total", {{"reason", "failed"}}, static_cast<double>(m.attemptsFailed));
    e.sample("pathfarm_attempts_ended_total", {{"reason", "released"}}, static_cast<double>(m.attemptsReleased));
}

void perJob(Exposition &e, const std::vector<v1::Job> &jobs) {
    const auto jobLabel = [](const v1::Job &j) { return Labels{{"job", std::to_string(j.id())}}; };
    e.family("pathfarm_job_info", "gauge", "One series per job naming its integrator, state and label.");
    for (const v1::Job &j : jobs)
        e.sample("pathfarm_job_info",
                 {{"job", std::to_string(j.id())},
                  {"integrator", j.integrator()},
                  {"state", farm::stateName(j.state())},
                  {"label", j.spec().label()}},
                 1);
    e.family("pathfarm_job_progress", "gauge", "Fraction of the job done (0..1).");
    for (const v1::Job &j : jobs) e.sample("pathfarm_job_progress", jobLabel(j), j.progress());
    // A Markov-chain job's budget is in mutations per pixel (pathfarm_job_mutations_per_pixel below).
    e.family("pathfarm_job_samples_per_pixel", "gauge", "Samples per pixel merged into an image job's film.");
    for (const v1::Job &j : jobs)
        if (!j.has_chain())
            e.sample("pathfarm_job_samples_per_pixel", jobLabel(j), static_cast<double>(j.samples_per_pixel()));
    e.family("pathfarm_job_render_seconds", "gauge", "Rendering time of the job: first lease to last merge.");
    for (const v1::Job &j : jobs) e.sample("pathfarm_job_render_seconds", jobLabel(j), j.render_seconds());
    e.family("pathfarm_job_samples_per_second", "gauge",
             "Pixel samples merged per second of the job's rendering time.");
    for (const v1::Job &j : jobs)
        e.sample("pathfarm_job_samples_per_second", jobLabel(j),
                 perSecond(static_cast<double>(j.samples()), j.render_seconds()));

    // Markov-chain jobs: acceptance per mutation type is the statistic ALGORITHMS.md §2.1 (step size) and
    // §9.2 (seed ranges for MEPT/MEMLT) judge chains by; §8.3 asks a farm to report it with mutations/s.
    // Each kind of a chain job's work in its own unit: seeding (BDPT samples), direct component (pixel
    // samples), chains (mutations).
    const auto byChainJob = [&](const char *name, const char *type, const char *help, auto value) {
        e.family(name, type, help);
        for (const v1::Job &j : jobs)
            if (j.has_chain()) e.sample(name, jobLabel(j), static_cast<double>(value(j.chain(), j)));
    };
    byChainJob("pathfarm_job_seeding_samples_total", "counter", "BDPT samples of a Markov-chain job's merged seeding.",
               [](const v1::ChainStats &c, const v1::Job &) { return c.seeding_samples(); });
    byChainJob("pathfarm_job_direct_samples_total", "counter",
               "Pixel samples of a Markov-chain job's merged direct component.",
               [](const v1::ChainStats &c, const v1::Job &) { return c.direct_samples(); });
    byChainJob("pathfarm_job_mutations_total", "counter", "Mutations merged into a Markov-chain job.",
               [](const v1::ChainStats &c, const v1::Job &) { return c.mutations(); });
    byChainJob("pathfarm_job_mutations_per_pixel", "gauge", "Mutations per pixel merged into a Markov-chain job.",
               [](const v1::ChainStats &c, const v1::Job &) { return c.mutations_per_pixel(); });
    byChainJob("pathfarm_job_mutations_per_second", "gauge", "Mutations merged per second of the job's rendering time.",
               [](const v1::ChainStats &c, const v1::Job &j) {
                   return perSecond(static_cast<double>(c.mutations()), j.render_seconds());
               });
    // A type never proposed has no acceptance ratio (rather than a misleading 0).
    const auto byMutation = [&](const char *name, const char *type, const char *help, bool onlyProposed, auto value) {
        e.family(name, type, help);
        for (const v1::Job &j : jobs)
            for (const v1::MutationCount &c : j.chain().mutation_counts())
                if (!onlyProposed || c.proposed() > 0)
                    e.sample(name, {{"job", std::to_string(j.id())}, {"mutation", c.name()}}, value(c));
    };
    byMutation("pathfarm_job_mutations_proposed_total", "counter", "Proposed mutations by type.", false,
               [](const v1::MutationCount &c) { return static_cast<double>(c.proposed()); });
    byMutation("pathfarm_job_mutations_accepted_total", "counter", "Accepted mutations by type.", false,
               [](const v1::MutationCount &c) { return static_cast<double>(c.accepted()); });
    byMutation("pathfarm_job_acceptance_ratio", "gauge", "Accepted over proposed mutations by type.", true,
               [](const v1::MutationCount &c) {
                   return static_cast<double>(c.accepted()) / static_cast<double>(c.proposed());
               });
}

}  // namespace

std::string prometheusText(const MasterMetrics &metrics, const std::vector<v1::Job> &jobs,
                           const std::vector<v1::WorkerInfo> &workers) {
    Exposition e;
    farmWide(e, metrics, jobs, workers);
    perJob(e, jobs);
    return e.str();
}

}  // namespace pf::master
