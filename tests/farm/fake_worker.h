// A worker driven by hand through the worker protocol, for tests that need one to go silent, deliver
// late, or deliver what it should not (tests/test_farm_recovery.cpp, tests/test_farm_hostile.cpp).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "farm/harness.h"
#include "farm/hash.h"

namespace pf::test::farm {

class FakeWorker {
public:
    // `algorithms`: the integrators it runs (empty: all).
    explicit FakeWorker(const Farm &farm, const std::vector<std::string> &algorithms = {})
        : farm_(farm), stub_(farm.workerStub(64 << 20)) {
        pathfarm::v1::RegisterRequest req;
        req.set_name("fake");
        for (const std::string &a : algorithms) req.add_algorithms(a);
        pathfarm::v1::RegisterReply reply;
        EXPECT_TRUE(stub_->Register(ctx().get(), req, &reply).ok());
        id_ = reply.worker_id();
    }
    const std::string &id() const { return id_; }
    std::optional<pathfarm::v1::TaskSpec> lease() {
        pathfarm::v1::LeaseRequest req;
        req.set_worker_id(id_);
        req.set_wait_ms(5000);
        pathfarm::v1::LeaseReply reply;
        EXPECT_TRUE(stub_->LeaseTask(ctx().get(), req, &reply).ok());
        return reply.has_task() ? std::make_optional(reply.task()) : std::nullopt;
    }
    // Up to `maxTasks` tasks in a row, for a batched result (tests/test_farm_batch.cpp).
    std::vector<pathfarm::v1::TaskSpec> leaseBatch(int maxTasks) {
        pathfarm::v1::LeaseRequest req;
        req.set_worker_id(id_);
        req.set_wait_ms(5000);
        req.set_max_tasks(maxTasks);
        pathfarm::v1::LeaseReply reply;
        EXPECT_TRUE(stub_->LeaseTask(ctx().get(), req, &reply).ok());
        std::vector<pathfarm::v1::TaskSpec> tasks;
        if (reply.has_task()) tasks.push_back(reply.task());
        tasks.insert(tasks.end(), reply.more().begin(), reply.more().end());
        return tasks;
    }
    // Delivers `payload` for `attempt` (and, batched with it, for `batch`); the call's status must be
    // `expected`.
    pathfarm::v1::CompleteReply complete(int64_t attempt, const std::string &payload,
                                         grpc::StatusCode expected = grpc::StatusCode::OK,
                                         const std::vector<int64_t> &batch = {}) {
        pathfarm::v1::CompleteReply reply;
        const auto c = ctx();
        auto writer = stub_->CompleteTask(c.get(), &reply);
        pathfarm::v1::ResultChunk chunk;
        chunk.mutable_header()->set_worker_id(id_);
        chunk.mutable_header()->set_attempt_id(attempt);
        for (const int64_t a : batch) chunk.mutable_header()->add_batch_attempt_ids(a);
        chunk.mutable_header()->set_payload_size(payload.size());
        chunk.mutable_header()->set_payload_hash(pf::farm::hashHex64(payload));
        if (writer->Write(chunk)) {
            chunk.set_data(payload);
            writer->Write(chunk);
            writer->WritesDone();
        }
        const grpc::Status s = writer->Finish();
        EXPECT_EQ(s.error_code(), expected) << s.error_message();
        lastError_ = s.error_message();
        return reply;
    }
    // A heartbeat holding `attempts`: the ones the master answers are lost.
    std::vector<int64_t> heartbeat(const std::vector<int64_t> &attempts) {
        pathfarm::v1::HeartbeatRequest req;
        req.set_worker_id(id_);
        for (const int64_t a : attempts) req.add_attempt_ids(a);
        pathfarm::v1::HeartbeatReply reply;
        EXPECT_TRUE(stub_->Heartbeat(ctx().get(), req, &reply).ok());
        return {reply.lost_attempt_ids().begin(), reply.lost_attempt_ids().end()};
    }
    const std::string &lastError() const { return lastError_; }

private:
    std::unique_ptr<grpc::ClientContext> ctx() const { return farm_.context(farm_.workerToken()); }
    const Farm &farm_;
    std::unique_ptr<pathfarm::v1::WorkerService::Stub> stub_;
    std::string id_, lastError_;
};

}  // namespace pf::test::farm
