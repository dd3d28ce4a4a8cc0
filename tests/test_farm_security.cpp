// Hostile and broken input against a real master process: missing and wrong tokens, bundles that reach
// outside themselves, oversize messages, malformed job specs and garbage results are all refused with a
// clear status, and the master keeps serving.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "farm/bundle.h"
#include "farm/harness.h"
#include "farm/hash.h"
#include "support/process.h"
#include "support/render_util.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using grpc::StatusCode;

class FarmSecurity : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        // CTest runs each test of the suite in a process of its own, possibly side by side.
        farm_ = new Farm("security-" + std::to_string(getpid()));
        farm_->startMaster({"--max-pixels", "10000", "--max-spp", "4096"});
        scene_ = writeTestScene(farm_->dir() + "/scene", 16, 8);
    }
    static void TearDownTestSuite() {
        // Whatever was thrown at it, the master is still up and answering.
        EXPECT_TRUE(farm_->master().running()) << farm_->master().log();
        v1::ListJobsReply reply;
        EXPECT_TRUE(farm_->clientStub()
                        ->ListJobs(farm_->context(farm_->clientToken()).get(), v1::ListJobsRequest(), &reply)
                        .ok());
        delete farm_;
    }

    // Uploads the test scene's bundle and returns its hash.
    static std::string uploadScene() {
        const auto [code, output] = farm_->cli("submit " + scene_ + " --spp 8");
        EXPECT_EQ(code, 0) << output;
        const std::string dir = farm_->dir() + "/scene";
        return pf::farm::bundleHash(pf::farm::makeManifest(dir, "scene.xml", pf::farm::collectSceneFiles(scene_, {})));
    }

    // Streams `manifest` followed by `data` as an upload; returns the status.
    static grpc::Status upload(const v1::BundleManifest &manifest, const std::string &data,
                               const std::string &token = farm_->clientToken()) {
        const auto stub = farm_->clientStub(64 << 20);
        v1::UploadBundleReply reply;
        const auto ctx = farm_->context(token);
        auto writer = stub->UploadBundle(ctx.get(), &reply);
        v1::BundleChunk chunk;
        *chunk.mutable_manifest() = manifest;
        if (writer->Write(chunk) && !data.empty()) {
            chunk.set_data(data);
            writer->Write(chunk);
        }
        writer->WritesDone();
        return writer->Finish();
    }

    static grpc::Status submit(const v1::JobSpec &spec) {
        v1::SubmitJobRequest req;
        *req.mutable_spec() = spec;
        v1::Job job;
        return farm_->clientStub()->SubmitJob(farm_->context(farm_->clientToken()).get(), req, &job);
    }

    static Farm *farm_;
    static std::string scene_;
};

Farm *FarmSecurity::farm_ = nullptr;
std::string FarmSecurity::scene_;

TEST_F(FarmSecurity, CallsWithoutTheRightTokenAreRefused) {
    const auto client = farm_->clientStub();
    const auto worker = farm_->workerStub();
    v1::ListJobsReply jobs;
    for (const std::string &token : {std::string(), std::string("wrong"), farm_->workerToken()}) {
        const grpc::Status s = client->ListJobs(farm_->context(token).get(), v1::ListJobsRequest(), &jobs);
        EXPECT_EQ(s.error_code(), StatusCode::UNAUTHENTICATED) << token;
    }
    v1::RegisterReply reg;
    for (const std::string &token : {std::string(), std::string("wrong"), farm_->clientToken()}) {
        const grpc::Status s = worker->Register(farm_->context(token).get(), v1::RegisterRequest(), &reg);
        EXPECT_EQ(s.error_code(), StatusCode::UNAUTHENTICATED) << token;
    }
    // A streaming call is refused before it reads anything.
    EXPECT_EQ(upload(v1::BundleManifest(), "", "wrong").error_code(), StatusCode::UNAUTHENTICATED);
    const auto r =
        runCommand("PATHFARM_MASTER=" + farm_->address() + " PATHFARM_TOKEN=wrong " + PATHFARM_CLI_BIN + " status");
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("wrong bearer token"), std::string::npos) << r.output;
    EXPECT_EQ(farm_->cli("status").first, 0);
}

TEST_F(FarmSecurity, BundleEntriesOutsideTheBundleAreRefused) {
    const std::string content = "v 0 0 0\n";
    for (const std::string &path : {std::string("../escape.obj"), std::string("/etc/passwd"),
                                    std::string("meshes/../../escape.obj"), std::string("a//b.obj")}) {
        v1::BundleManifest m;
        m.set_scene_file(path);
        auto *e = m.add_entries();
        e->set_path(path);
        e->set_size(content.size());
        e->set_hash(pf::farm::hashHex64(content));
        const grpc::Status s = upload(m, content);
        EXPECT_EQ(s.error_code(), StatusCode::INVALID_ARGUMENT) << path;
        EXPECT_NE(s.error_message().find("cannot reach outside"), std::string::npos) << s.error_message();
    }
    EXPECT_FALSE(std::filesystem::exists(farm_->dir() + "/data/escape.obj"));
    EXPECT_FALSE(std::filesystem::exists(farm_->dir() + "/escape.obj"));

    // A scene that names a file outside its directory is refused by the master's loader, naming it.
    const std::string dir = farm_->dir() + "/escaping";
    std::filesystem::create_directories(dir);
    writeFile(farm_->dir(), "outside.obj", content);
    const std::string scene = writeFile(dir, "scene.xml", R"(<scene version="0.6.0">
  <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>
    <integer name="height" value="8"/></film></sensor>
  <shape type="obj"><string name="filename" value="../outside.obj"/></shape>
</scene>
)");
    const auto [code, output] = farm_->cli("submit " + scene + " --spp 1");
    EXPECT_EQ(code, 2) << output;
    EXPECT_NE(output.find("outside.obj"), std::string::npos) << output;
}

TEST_F(FarmSecurity, BundleContentMustMatchItsManifest) {
    v1::BundleManifest m;
    m.set_scene_file("scene.xml");
    auto *e = m.add_entries();
    e->set_path("scene.xml");
    e->set_size(5);
    e->set_hash(pf::farm::hashHex64("hello"));
    EXPECT_EQ(upload(m, "jello").error_code(), StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(upload(m, "hello, and more").error_code(), StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(upload(m, "hel").error_code(), StatusCode::INVALID_ARGUMENT);
    EXPECT_TRUE(upload(m, "hello").ok());
}

TEST_F(FarmSecurity, OversizeMessagesAreRefused) {
    v1::BundleManifest m;
    m.set_scene_file("scene.xml");
    auto *e = m.add_entries();
    e->set_path("scene.xml");
    const std::string big(5 << 20, 'x');  // over the master's 4 MiB limit
    e->set_size(big.size());
    e->set_hash(pf::farm::hashHex64(big));
    EXPECT_EQ(upload(m, big).error_code(), StatusCode::RESOURCE_EXHAUSTED);
}

TEST_F(FarmSecurity, MalformedJobSpecsGetClearErrors) {
    const std::string hash = uploadScene();
    struct Case {
        std::function<void(v1::JobSpec &)> edit;
        std::string expected;
    };
    const std::vector<Case> cases = {
        {[](v1::JobSpec &s) { s.clear_bundle_hash(); }, "bundle_hash is missing"},
        {[](v1::JobSpec &s) { s.set_bundle_hash("../../etc"); }, "unknown bundle"},
        {[](v1::JobSpec &s) { s.mutable_budget()->set_spp(-3); }, "spp must be in"},
        {[](v1::JobSpec &s) { s.mutable_budget()->set_spp(100000); }, "spp must be in"},
        {[](v1::JobSpec &s) { s.mutable_budget()->set_time_seconds(std::nan("")); }, "time budget"},
        {[](v1::JobSpec &s) { s.set_integrator("nosuch"); }, "unknown integrator 'nosuch'"},
        {[](v1::JobSpec &s) {
             auto *p = s.add_params();
             p->set_name("maxDepth");
             p->set_value("deep");
         },
         "maxDepth"},
        {[](v1::JobSpec &s) {
             // Only a strict job refuses an unused parameter; see UnusedParametersAreWarningsUnlessStrict.
             s.set_strict(true);
             auto *p = s.add_params();
             p->set_name("noSuchParameter");
             p->set_value("1");
         },
         "unknown parameter 'noSuchParameter'"},
        {[](v1::JobSpec &s) {
             auto *d = s.add_defines();
             d->set_name("res");
             d->set_value("1000");
         },
         "exceed this master's limit"},
        {[](v1::JobSpec &s) {
             auto *d = s.add_defines();
             d->set_name("res");
             d->set_value("-4");
         },
         "scene.xml"},
    };
    for (const Case &c : cases) {
        v1::JobSpec spec;
        spec.set_bundle_hash(hash);
        c.edit(spec);
        const grpc::Status s = submit(spec);
        EXPECT_EQ(s.error_code(), StatusCode::INVALID_ARGUMENT) << c.expected;
        EXPECT_NE(s.error_message().find(c.expected), std::string::npos) << s.error_message();
    }
    // Malformed XML is reported with its file and line, through the CLI as a user sees it.
    std::filesystem::create_directories(farm_->dir() + "/malformed");
    const std::string bad = writeFile(farm_->dir() + "/malformed", "scene.xml", "<scene version=\"0.6.0\">\n<shape>\n");
    const auto [code, output] = farm_->cli("submit " + bad + " --spp 1");
    EXPECT_EQ(code, 2) << output;
    EXPECT_NE(output.find("scene.xml"), std::string::npos) << output;
}

// The master loads a job as `pathfarm render` does: a parameter that no plugin uses is a warning in the
// job record unless the spec is strict (pathfarm submit --strict), when the job is refused.
TEST_F(FarmSecurity, UnusedParametersAreWarningsUnlessStrict) {
    v1::SubmitJobRequest req;
    v1::JobSpec &spec = *req.mutable_spec();
    spec.set_bundle_hash(uploadScene());
    spec.mutable_budget()->set_spp(1);
    auto *p = spec.add_params();
    p->set_name("noSuchParameter");
    p->set_value("1");
    v1::Job job;
    ASSERT_TRUE(farm_->clientStub()->SubmitJob(farm_->context(farm_->clientToken()).get(), req, &job).ok());
    ASSERT_EQ(job.warnings_size(), 1);
    EXPECT_NE(job.warnings(0).find("unused parameter 'noSuchParameter'"), std::string::npos) << job.warnings(0);
    spec.set_strict(true);
    EXPECT_EQ(submit(spec).error_code(), StatusCode::INVALID_ARGUMENT);
    // Through the CLI, as a user sees it: a warning on stderr, or exit 2 with --strict.
    const auto [code, output] = farm_->cli("submit " + scene_ + " --spp 1 -P noSuchParameter=1");
    EXPECT_EQ(code, 0) << output;
    EXPECT_NE(output.find("warning: command line (-P noSuchParameter=1): path: unused parameter 'noSuchParameter'"),
              std::string::npos)
        << output;
    const auto [strictCode, strictOutput] = farm_->cli("submit " + scene_ + " --spp 1 --strict -P noSuchParameter=1");
    EXPECT_EQ(strictCode, 2) << strictOutput;
    EXPECT_NE(strictOutput.find("unknown parameter 'noSuchParameter'"), std::string::npos) << strictOutput;
}

TEST_F(FarmSecurity, GarbageFromWorkersIsRefused) {
    const auto worker = farm_->workerStub();
    v1::RegisterRequest req;
    req.set_name("garbage");
    v1::RegisterReply reg;
    ASSERT_TRUE(worker->Register(farm_->context(farm_->workerToken()).get(), req, &reg).ok());

    v1::CompleteReply reply;
    {
        const auto ctx = farm_->context(farm_->workerToken());
        auto writer = worker->CompleteTask(ctx.get(), &reply);
        v1::ResultChunk chunk;
        chunk.mutable_header()->set_worker_id(reg.worker_id());
        chunk.mutable_header()->set_attempt_id(987654);
        writer->Write(chunk);
        writer->WritesDone();
        EXPECT_TRUE(writer->Finish().ok());
        EXPECT_FALSE(reply.accepted());
        EXPECT_NE(reply.reason().find("unknown attempt"), std::string::npos) << reply.reason();
    }
    {
        const auto ctx = farm_->context(farm_->workerToken());
        auto writer = worker->CompleteTask(ctx.get(), &reply);
        v1::ResultChunk chunk;
        chunk.set_data("no header");
        writer->Write(chunk);
        writer->WritesDone();
        EXPECT_EQ(writer->Finish().error_code(), StatusCode::INVALID_ARGUMENT);
    }
    v1::FetchBundleRequest fetch;
    fetch.set_hash("../../store.sqlite");
    const auto ctx = farm_->context(farm_->workerToken());
    auto reader = worker->FetchBundle(ctx.get(), fetch);
    v1::BundleChunk chunk;
    EXPECT_FALSE(reader->Read(&chunk));
    EXPECT_EQ(reader->Finish().error_code(), StatusCode::NOT_FOUND);
    v1::HeartbeatRequest hb;
    hb.set_worker_id("w-nobody");
    v1::HeartbeatReply hbReply;
    EXPECT_EQ(worker->Heartbeat(farm_->context(farm_->workerToken()).get(), hb, &hbReply).error_code(),
              StatusCode::NOT_FOUND);
}

TEST_F(FarmSecurity, HealthServiceAnswers) {
    const auto [code, output] = farm_->cli("health");
    EXPECT_EQ(code, 0) << output;
    EXPECT_NE(output.find("SERVING"), std::string::npos) << output;
}

}  // namespace
}  // namespace pf::test::farm
