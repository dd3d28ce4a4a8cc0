// Hostile clients against a real master (issue 18, item 5; test_farm_security covers tokens, oversize gRPC
// messages, malformed specs and garbage results): a worker that delivers for a task it never leased or a
// result of another job is refused and nothing of it is merged; slow and silent HTTP clients, watch
// streams that are never read and many concurrent calls neither crash the master nor hold up a job or
// the status pages for others; oversize and malformed HTTP requests are refused.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "farm/block_codec.h"
#include "farm/fake_worker.h"
#include "farm/harness.h"
#include "integrators/integrator.h"
#include "render/image_task.h"
#include "scene/scene.h"

namespace pf::test::farm {
namespace {

namespace v1 = pathfarm::v1;
using namespace std::chrono_literals;

// The one task of `scene` at --spp 8 --seed 2, rendered here exactly as a worker renders it.
std::string renderTask(const std::string &scene) {
    auto loaded = loadScene(scene);
    const auto integrator = createIntegrator("path", loaded->integratorProperties(), true);
    const ImageTaskResult result =
        runImageTask(*loaded, dynamic_cast<const SamplingIntegrator &>(*integrator), 2, ImageTask{0, 8}, 1);
    return pf::farm::encodeBlock(result.block);
}

// A job of `scene` at --spp 8 --seed 2 (one task), with its embedded render as reference.
struct OneTaskJob {
    OneTaskJob(const Farm &farm, const std::string &name, int res)
        : scene(writeTestScene(farm.dir() + "/" + name, res, 8)),
          reference(farm.embeddedRender(scene, "--spp 8 --seed 2", name)),
          payload(renderTask(scene)) {
        const auto [code, output] = farm.cli("submit " + scene + " --spp 8 --seed 2");
        EXPECT_EQ(code, 0) << output;
        id = jobIdFrom(output);
    }
    void expectDoneExactly(const Farm &farm) const {
        ASSERT_EQ(farm.waitForJob(id, 30s).state(), v1::JOB_DONE);
        const std::string out = farm.dir() + "/job-" + std::to_string(id) + ".exr";
        const auto [code, output] = farm.cli("fetch " + std::to_string(id) + " -o " + out);
        ASSERT_EQ(code, 0) << output;
        EXPECT_TRUE(sameBits(reference, out));
        EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM merges WHERE job_id = " + std::to_string(id)), 1);
    }
    std::string scene, reference, payload;
    int64_t id = -1;
};

TEST(FarmHostile, ResultsForATaskTheWorkerNeverLeasedAreRefused) {
    Farm farm("hostile-unleased");
    farm.startMaster({"--lease-ms", "800", "--heartbeat-ms", "100"});
    const OneTaskJob job(farm, "a", 16);
    FakeWorker owner(farm), intruder(farm);
    const auto lease = owner.lease();
    ASSERT_TRUE(lease);
    const int64_t attempt = lease->attempt_id();

    // Another worker delivers for the owner's attempt, live and then expired (the owner never renews it,
    // and no other worker has the task yet), and for an attempt that never existed.
    v1::CompleteReply r = intruder.complete(attempt, job.payload);
    EXPECT_FALSE(r.accepted());
    EXPECT_NE(r.reason().find("was not leased to worker"), std::string::npos) << r.reason();
    ASSERT_TRUE(waitUntil(
        [&] {
            return farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'expired' AND id = " +
                                   std::to_string(attempt)) == 1;
        },
        30s));
    r = intruder.complete(attempt, job.payload);
    EXPECT_FALSE(r.accepted());
    EXPECT_NE(r.reason().find("was not leased to worker"), std::string::npos) << r.reason();
    r = intruder.complete(attempt + 1000, job.payload);
    EXPECT_FALSE(r.accepted());
    EXPECT_NE(r.reason().find("unknown attempt"), std::string::npos) << r.reason();
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM results"), 0);

    // The owner's own late result still counts (its task was not given to anyone else).
    EXPECT_TRUE(owner.complete(attempt, job.payload).accepted());
    job.expectDoneExactly(farm);
    EXPECT_TRUE(farm.master().running());
}

TEST(FarmHostile, AResultOfAnotherJobIsRefused) {
    Farm farm("hostile-other-job");
    farm.startMaster();
    const OneTaskJob a(farm, "a", 16), b(farm, "b", 24);
    FakeWorker worker(farm);
    const auto first = worker.lease();
    ASSERT_TRUE(first);
    ASSERT_EQ(first->job_id(), a.id);
    // Job b's film is 24 x 24: its block does not fit job a's 16 x 16 film.
    worker.complete(first->attempt_id(), b.payload, grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(worker.lastError().find("corrupt result"), std::string::npos) << worker.lastError();
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM results"), 0);
    EXPECT_EQ(farm.queryStore("SELECT COUNT(*) FROM attempts WHERE state = 'failed'"), 1);

    // The task is leased again, and the right results make both jobs exact.
    for (int i = 0; i < 2; ++i) {
        const auto task = worker.lease();
        ASSERT_TRUE(task);
        EXPECT_TRUE(worker.complete(task->attempt_id(), task->job_id() == a.id ? a.payload : b.payload).accepted());
    }
    a.expectDoneExactly(farm);
    b.expectDoneExactly(farm);
}

// A TCP connection to 127.0.0.1:port that sends `bytes` and then nothing; closed on destruction.
class RawConnection {
public:
    RawConnection(int port, const std::string &bytes) : fd_(::socket(AF_INET, SOCK_STREAM, 0)) {
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_port = htons(static_cast<uint16_t>(port));
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        connected_ = ::connect(fd_, reinterpret_cast<sockaddr *>(&addr), sizeof addr) == 0 &&
                     ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
    }
    ~RawConnection() { ::close(fd_); }
    RawConnection(const RawConnection &) = delete;
    RawConnection &operator=(const RawConnection &) = delete;
    bool connected() const { return connected_; }
    // The status line of the answer, waiting up to `timeout` for it ("" if none).
    std::string statusLine(std::chrono::seconds timeout) const {
        timeval tv{static_cast<time_t>(timeout.count()), 0};
        ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
        char buf[256];
        const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
        const std::string got(buf, n > 0 ? static_cast<size_t>(n) : 0);
        return got.substr(0, got.find("\r\n"));
    }

private:
    int fd_;
    bool connected_ = false;
};

TEST(FarmHostile, SlowAndManyClientsHoldUpNobody) {
    Farm farm("hostile-slow");
    const int httpPort = freePort();
    farm.startMaster({"--http", "127.0.0.1:" + std::to_string(httpPort)});
    const std::string scene = writeTestScene(farm.dir() + "/scene", 64, 8);
    const std::string spec = "--spp 64 --seed 4";
    const std::string reference = farm.embeddedRender(scene, spec, "reference");

    // Status-page clients that never finish their request, or never send one.
    std::vector<std::unique_ptr<RawConnection>> slow;
    for (int i = 0; i < 24; ++i) {
        slow.push_back(std::make_unique<RawConnection>(httpPort, "GET /api/v1/jobs HTTP/1.1\r\nHost: x\r\n"));
        slow.push_back(std::make_unique<RawConnection>(httpPort, ""));
    }
    for (const auto &c : slow) ASSERT_TRUE(c->connected());
    // Oversize and malformed requests are answered with an error, not read without end.
    RawConnection huge(httpPort, "POST /api/v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Length: 1000000000\r\n\r\n" +
                                     std::string(1 << 16, 'x'));
    RawConnection garbage(httpPort, std::string("\x16\x03\x01\x02\x00 garbage\r\n\r\n", 20));
    RawConnection longHeader(httpPort, "GET / HTTP/1.1\r\nX: " + std::string(1 << 16, 'y') + "\r\n\r\n");
    EXPECT_NE(huge.statusLine(10s).find(" 413"), std::string::npos);
    EXPECT_NE(garbage.statusLine(10s).find(" 400"), std::string::npos);
    EXPECT_NE(longHeader.statusLine(10s).find(" 4"), std::string::npos);

    // A job rendered meanwhile, watched by clients that never read their streams.
    farm.startWorker(1);
    const auto [code, output] = farm.cli("submit " + scene + " " + spec);
    ASSERT_EQ(code, 0) << output;
    const int64_t id = jobIdFrom(output);
    const auto stub = farm.clientStub();
    std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
    std::vector<std::unique_ptr<grpc::ClientReader<v1::Job>>> watchers;
    for (int i = 0; i < 32; ++i) {
        contexts.push_back(farm.context(farm.clientToken(), 600));
        v1::WatchJobRequest req;
        req.set_id(id);
        watchers.push_back(stub->WatchJob(contexts.back().get(), req));
    }
    // Many concurrent calls, while the status page answers promptly throughout.
    std::vector<std::thread> callers;
    std::atomic<int> answered{0};
    for (int i = 0; i < 64; ++i)
        callers.emplace_back([&] {
            v1::GetJobRequest req;
            req.set_id(id);
            v1::Job job;
            answered += farm.clientStub()->GetJob(farm.context(farm.clientToken()).get(), req, &job).ok();
        });
    httplib::Client http("127.0.0.1", httpPort);
    http.set_connection_timeout(1, 0);
    http.set_read_timeout(1, 0);
    for (int i = 0; i < 20; ++i) {
        const auto res = http.Get("/api/v1/jobs/" + std::to_string(id));
        EXPECT_TRUE(res) << "the status page did not answer within a second";
        if (!res) break;  // (the callers are joined below)
        EXPECT_EQ(res->status, 200);
        std::this_thread::sleep_for(100ms);
    }
    for (std::thread &t : callers) t.join();
    EXPECT_EQ(answered, 64);

    EXPECT_EQ(farm.waitForJob(id, 120s).state(), v1::JOB_DONE);
    const std::string out = farm.dir() + "/farm.exr";
    const auto [fcode, fetched] = farm.cli("fetch " + std::to_string(id) + " -o " + out);
    ASSERT_EQ(fcode, 0) << fetched;
    EXPECT_TRUE(sameBits(reference, out));
    for (auto &c : contexts) c->TryCancel();
    EXPECT_TRUE(farm.master().running());
}

}  // namespace
}  // namespace pf::test::farm
