// The master's HTTP status with real processes: JSON derived from the proto messages, Prometheus
// metrics (checked against the exposition format and against the job's own record), liveness and
// readiness, the dashboard page and a preview PNG of the job's image.
#include <gtest/gtest.h>
#include <httplib.h>
#include <signal.h>

#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "farm/harness.h"
#include "image/bitmap.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;

// GETs on the master's HTTP port: status and body (status 0 when nothing answered).
class HttpGet {
public:
    explicit HttpGet(int port) : http_("127.0.0.1", port) { http_.set_read_timeout(10, 0); }
    std::pair<int, std::string> operator()(const std::string &path) {
        const auto res = http_.Get(path);
        EXPECT_TRUE(res) << path;
        return res ? std::make_pair(res->status, res->body) : std::make_pair(0, std::string());
    }

private:
    httplib::Client http_;
};

// Parses a Prometheus text exposition (format 0.0.4) into sample -> value, where a sample is written
// `name{label="value",...}` as in the text. Fails the test on a line that breaks the format: a sample
// whose family has no HELP and TYPE before it, a malformed name, label set or value, a sample twice.
std::map<std::string, double> parseExposition(const std::string &text) {
    static const std::regex help(R"(# HELP ([a-zA-Z_:][a-zA-Z0-9_:]*) .+)");
    static const std::regex type(R"(# TYPE ([a-zA-Z_:][a-zA-Z0-9_:]*) (counter|gauge|summary|histogram|untyped))");
    static const std::regex sample(
        R"(([a-zA-Z_:][a-zA-Z0-9_:]*)(\{[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\.)*"(?:,[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\.)*")*\})? (-?[0-9.eE+-]+|NaN|[+-]Inf))");
    std::set<std::string> helped, typed;
    std::map<std::string, double> out;
    std::istringstream in(text);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
        ++n;
        std::smatch m;
        if (std::regex_match(line, m, help)) {
            EXPECT_TRUE(helped.insert(m[1]).second) << "line " << n << ": second HELP for " << m[1];
        } else if (std::regex_match(line, m, type)) {
            EXPECT_TRUE(typed.insert(m[1]).second) << "line " << n << ": second TYPE for " << m[1];
        } else if (std::regex_match(line, m, sample)) {
            std::string family = m[1];
            for (const char *suffix : {"_sum", "_count"})
                if (!typed.count(family) && family.ends_with(suffix))
                    family = family.substr(0, family.size() - std::strlen(suffix));
            EXPECT_TRUE(helped.count(family) && typed.count(family)) << "line " << n << ": no HELP/TYPE: " << line;
            EXPECT_TRUE(out.emplace(std::string(m[1]) + std::string(m[2]), std::stod(m[3])).second)
                << "line " << n << ": repeated sample " << line;
        } else {
            ADD_FAILURE() << "line " << n << " is not in the exposition format: '" << line << "'";
        }
    }
    return out;
}

// A master serving its HTTP status, one worker, and a job rendered to completion on the farm tests'
// scene.
class FarmHttp : public ::testing::Test {
protected:
    // Returns the job's id, or "" after failing the test.
    std::string renderJob(int workerThreads, int res, int spp, const std::string &submitArgs) {
        farm = std::make_unique<Farm>(::testing::UnitTest::GetInstance()->current_test_info()->name());
        port = freePort();
        farm->startMaster({"--http", "127.0.0.1:" + std::to_string(port)});
        farm->startWorker(workerThreads);
        const std::string scene = writeTestScene(farm->dir() + "/scene", res, spp);
        const auto [code, output] =
            farm->cli("submit " + scene + " " + submitArgs + " --wait -o " + farm->dir() + "/out.exr");
        EXPECT_EQ(code, 0) << output << farm->master().log();
        return code == 0 ? std::to_string(jobIdFrom(output)) : "";
    }
    std::unique_ptr<Farm> farm;
    int port = 0;
};

TEST_F(FarmHttp, StatusPagesShowJobsWorkersAndAPreview) {
    const std::string id = renderJob(1, 32, 8, "--spp 16 --label http-test");
    ASSERT_FALSE(id.empty());

    HttpGet get(port);
    EXPECT_EQ(get("/livez").first, 200);
    EXPECT_EQ(get("/readyz").first, 200);

    const auto [jobsStatus, jobs] = get("/api/v1/jobs");
    EXPECT_EQ(jobsStatus, 200);
    EXPECT_NE(jobs.find("\"label\":\"http-test\""), std::string::npos) << jobs;
    const auto [jobStatus, jobText] = get("/api/v1/jobs/" + id);
    EXPECT_EQ(jobStatus, 200);
    const json job = json::parse(jobText);
    EXPECT_EQ(job["state"], "JOB_DONE") << jobText;
    EXPECT_EQ(job["samples_per_pixel"], "16") << jobText;
    EXPECT_EQ(get("/api/v1/jobs/999").first, 404);
    const auto [workersStatus, workers] = get("/api/v1/workers");
    EXPECT_NE(workers.find("\"name\":\"worker-0\""), std::string::npos) << workers;

    const auto [pageStatus, page] = get("/");
    EXPECT_EQ(pageStatus, 200);
    EXPECT_NE(page.find("<title>pathfarm</title>"), std::string::npos);

    // The preview is a real PNG of the job's image, not a blank one.
    const auto [pngStatus, png] = get("/api/v1/jobs/" + id + "/preview.png");
    ASSERT_EQ(pngStatus, 200);
    const std::string pngPath = writeFile(farm->dir(), "preview.png", png);
    const Bitmap preview = readLDR(pngPath, false);
    EXPECT_EQ(preview.width, 32);
    float brightest = 0;
    for (const float v : preview.rgb) brightest = std::max(brightest, v);
    EXPECT_GT(brightest, 0.1f);
    EXPECT_EQ(get("/api/v1/jobs/999/preview.png").first, 404);
}

TEST_F(FarmHttp, MetricsAgreeWithTheJobAndTheWorkers) {
    const std::string id = renderJob(2, 32, 8, "--spp 24 --label \"metrics \\\"q\\\"\"");
    ASSERT_FALSE(id.empty());
    HttpGet get(port);
    const json job = json::parse(get("/api/v1/jobs/" + id).second);
    const double tasks = std::stod(job["tasks"]["total"].get<std::string>());
    ASSERT_GT(tasks, 0);

    const auto [status, text] = get("/metrics");
    ASSERT_EQ(status, 200);
    const std::map<std::string, double> m = parseExposition(text);
    auto value = [&](const std::string &sample) {
        const auto it = m.find(sample);
        EXPECT_NE(it, m.end()) << "no sample " << sample << " in\n" << text;
        return it == m.end() ? -1.0 : it->second;
    };
    // Tasks and jobs by state.
    EXPECT_EQ(value("pathfarm_tasks{state=\"merged\"}"), tasks);
    EXPECT_EQ(value("pathfarm_tasks{state=\"pending\"}"), 0);
    EXPECT_EQ(value("pathfarm_tasks{state=\"leased\"}"), 0);
    EXPECT_EQ(value("pathfarm_jobs{state=\"done\"}"), 1);
    // Workers: one, waiting for work, with its two threads.
    EXPECT_EQ(value("pathfarm_workers{state=\"idle\"}"), 1);
    EXPECT_EQ(value("pathfarm_workers{state=\"busy\"}"), 0);
    EXPECT_EQ(value("pathfarm_workers{state=\"lost\"}"), 0);
    EXPECT_EQ(value("pathfarm_worker_threads"), 2);
    // Samples and their rate: 32 x 32 pixels x 24 spp, merged within the last minute.
    const double samples = 32 * 32 * 24;
    EXPECT_EQ(value("pathfarm_samples_merged_total"), samples);
    EXPECT_NEAR(value("pathfarm_samples_per_second"), samples / 60.0, 1e-6 * samples);
    // Merge time: one observation per merged result.
    EXPECT_EQ(value("pathfarm_merge_seconds_count"), tasks);
    EXPECT_GT(value("pathfarm_merge_seconds_sum"), 0);
    EXPECT_GT(value("pathfarm_result_bytes_total"), 0);
    EXPECT_EQ(value("pathfarm_attempts_ended_total{reason=\"expired\"}"), 0);
    // The job's own series, its label escaped as the format wants.
    const std::string j = "{job=\"" + id + "\"}";
    EXPECT_EQ(
        value("pathfarm_job_info{job=\"" + id + "\",integrator=\"path\",state=\"done\",label=\"metrics \\\"q\\\"\"}"),
        1);
    EXPECT_EQ(value("pathfarm_job_progress" + j), 1);
    EXPECT_EQ(value("pathfarm_job_samples_per_pixel" + j), 24);
    EXPECT_NEAR(value("pathfarm_job_render_seconds" + j), job["render_seconds"].get<double>(), 1e-9);
    EXPECT_NEAR(value("pathfarm_job_samples_per_second" + j), samples / job["render_seconds"].get<double>(),
                1e-6 * value("pathfarm_job_samples_per_second" + j));
    // An image job has no mutations.
    EXPECT_EQ(m.count("pathfarm_job_mutations_total" + j), 0u);
}

// A Markov-chain job on the farm: its mutation counts and acceptance ratios per mutation type reach the
// JSON record and /metrics, and the two agree.
TEST_F(FarmHttp, ChainJobsReportMutationsAndAcceptance) {
    const std::string id = renderJob(2, 24, 4, "--integrator pssmlt --spp 4");
    ASSERT_FALSE(id.empty());
    HttpGet get(port);
    const json job = json::parse(get("/api/v1/jobs/" + id).second);
    ASSERT_TRUE(job.contains("chain")) << job.dump();
    const double mutations = std::stod(job["chain"]["mutations"].get<std::string>());
    EXPECT_GT(mutations, 0);

    const std::map<std::string, double> m = parseExposition(get("/metrics").second);
    const std::string j = "{job=\"" + id + "\"}";
    EXPECT_EQ(m.at("pathfarm_job_mutations_total" + j), mutations);
    EXPECT_EQ(m.at("pathfarm_mutations_merged_total"), mutations);
    // Units apart: mutations per pixel instead of samples per pixel; the seeding's BDPT samples and the
    // direct component's pixel samples are the job's (and the farm's) samples, never the mutations.
    EXPECT_EQ(m.count("pathfarm_job_samples_per_pixel" + j), 0u);
    EXPECT_EQ(m.at("pathfarm_job_mutations_per_pixel" + j),
              std::stod(job["chain"]["mutations_per_pixel"].get<std::string>()));
    const double seeding = std::stod(job["chain"]["seeding_samples"].get<std::string>());
    const double direct = std::stod(job["chain"]["direct_samples"].get<std::string>());
    EXPECT_GT(seeding, 0);
    EXPECT_EQ(m.at("pathfarm_job_seeding_samples_total" + j), seeding);
    EXPECT_EQ(m.at("pathfarm_job_direct_samples_total" + j), direct);
    EXPECT_EQ(std::stod(job["samples"].get<std::string>()), seeding + direct);
    EXPECT_EQ(m.at("pathfarm_samples_merged_total"), seeding + direct);
    EXPECT_NEAR(m.at("pathfarm_job_mutations_per_second" + j), mutations / job["render_seconds"].get<double>(),
                1e-6 * m.at("pathfarm_job_mutations_per_second" + j));
    ASSERT_FALSE(job["chain"]["mutation_counts"].empty()) << job.dump();
    double proposedAll = 0;
    for (const json &c : job["chain"]["mutation_counts"]) {
        const std::string labels = "{job=\"" + id + "\",mutation=\"" + c["name"].get<std::string>() + "\"}";
        const double proposed = std::stod(c["proposed"].get<std::string>());
        const double accepted = std::stod(c["accepted"].get<std::string>());
        proposedAll += proposed;
        EXPECT_EQ(m.at("pathfarm_job_mutations_proposed_total" + labels), proposed);
        EXPECT_EQ(m.at("pathfarm_job_mutations_accepted_total" + labels), accepted);
        // A type never proposed has no ratio.
        const auto ratio = m.find("pathfarm_job_acceptance_ratio" + labels);
        ASSERT_EQ(ratio != m.end(), proposed > 0) << labels;
        if (proposed == 0) continue;
        EXPECT_NEAR(ratio->second, accepted / proposed, 1e-9);
        EXPECT_GE(ratio->second, 0);
        EXPECT_LE(ratio->second, 1);
    }
    // Every mutation proposed is one step of a chain.
    EXPECT_EQ(proposedAll, mutations);
}

// Readiness is about taking new work: from SIGTERM on, while the master finishes the calls in flight
// (here a client watching a running job holds it for the shutdown deadline), /readyz answers 503 and
// /livez still 200, so that an orchestrator stops routing to it without restarting it.
TEST(FarmHttpShutdown, ReadinessFailsWhileTheMasterDrains) {
    Farm farm("shutdown");
    const int port = freePort();
    farm.startMaster({"--http", "127.0.0.1:" + std::to_string(port)});
    farm.startWorker(1);
    const std::string scene = writeTestScene(farm.dir() + "/scene", 32, 8);
    const auto [code, output] = farm.cli("submit " + scene + " --time 60");
    ASSERT_EQ(code, 0) << output;
    const auto stub = farm.clientStub();
    const auto ctx = farm.context(farm.clientToken());
    pathfarm::v1::WatchJobRequest req;
    req.set_id(jobIdFrom(output));
    const auto watch = stub->WatchJob(ctx.get(), req);
    pathfarm::v1::Job job;
    ASSERT_TRUE(watch->Read(&job));

    HttpGet get(port);
    EXPECT_EQ(get("/readyz").first, 200);
    farm.master().signal(SIGTERM);
    EXPECT_TRUE(waitUntil([&] { return get("/readyz").first == 503; }, 3s)) << farm.master().log();
    EXPECT_EQ(get("/livez").first, 200);
    ctx->TryCancel();
    EXPECT_EQ(farm.master().wait(15s), 0) << farm.master().log();
}

// A port something already listens on is refused with an error naming it: a second master on the first one's
// address, a worker's health service there, and a status port equal to the gRPC port. Sharing a port (SO_REUSEPORT, the
// default of both gRPC and httplib) would split the connections between the listeners.
TEST(FarmPorts, AnAddressInUseIsRefused) {
    Farm farm("ports");
    farm.startMaster();
    const auto refused = [&](const std::vector<std::string> &extra) {
        std::vector<std::string> argv = {
            PATHFARM_MASTER_BIN,        "--listen",     farm.address(),         "--data",
            farm.dir() + "/other-data", "--token-file", farm.clientTokenFile(), "--worker-token-file",
            farm.workerTokenFile()};
        argv.insert(argv.end(), extra.begin(), extra.end());
        Process second(argv, farm.dir() + "/second-" + std::to_string(argv.size()) + ".log");
        const auto code = second.wait(30s);
        return std::make_pair(code ? *code : -999, second.log());
    };
    const auto [code, log] = refused({});
    EXPECT_EQ(code, 1) << log;
    EXPECT_NE(log.find("cannot listen on " + farm.address()), std::string::npos) << log;
    EXPECT_TRUE(farm.master().running());

    Process worker({PATHFARM_WORKER_BIN, "--master", farm.address(), "--token-file", farm.workerTokenFile(),
                    "--health-listen", farm.address()},
                   farm.dir() + "/worker.log");
    EXPECT_EQ(worker.wait(30s), 1) << worker.log();
    EXPECT_NE(worker.log().find("cannot listen on " + farm.address()), std::string::npos) << worker.log();

    Farm other("ports-http");
    const std::string same = other.address();
    Process master({PATHFARM_MASTER_BIN, "--listen", same, "--http", same, "--data", other.dir() + "/data",
                    "--token-file", other.clientTokenFile(), "--worker-token-file", other.workerTokenFile()},
                   other.dir() + "/master.log");
    const auto httpCode = master.wait(30s);
    EXPECT_EQ(httpCode, 1) << master.log();
    EXPECT_NE(master.log().find("cannot listen on " + same + " for HTTP"), std::string::npos) << master.log();
}

}  // namespace
}  // namespace pf::test::farm
