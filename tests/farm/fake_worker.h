// A worker driven by hand through the worker protocol, for tests that need one to go silent, deliver
// late, or deliver what it should not (tests/test_farm_recovery.cpp, tests/test_farm_hostile.cpp).
#pragma once
#include <optional>
#include <string>

#include "farm/harness.h"
#include "farm/hash.h"

namespace pf::test::farm {

class FakeWorker {
public:
    explicit FakeWorker(const Farm &farm) : farm_(farm), stub_(farm.workerStub(64 << 20)) {
        pathfarm::v1::RegisterRequest req;
        req.set_name("fake");
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
    // Delivers `payload` for `attempt`; the call's status must be `expected`.
    pathfarm::v1::CompleteReply complete(int64_t attempt, const std::string &payload,
                                         grpc::StatusCode expected = grpc::StatusCode::OK) {
        pathfarm::v1::CompleteReply reply;
        const auto c = ctx();
        auto writer = stub_->CompleteTask(c.get(), &reply);
        pathfarm::v1::ResultChunk chunk;
        chunk.mutable_header()->set_worker_id(id_);
        chunk.mutable_header()->set_attempt_id(attempt);
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
    const std::string &lastError() const { return lastError_; }

private:
    std::unique_ptr<grpc::ClientContext> ctx() const { return farm_.context(farm_.workerToken()); }
    const Farm &farm_;
    std::unique_ptr<pathfarm::v1::WorkerService::Stub> stub_;
    std::string id_, lastError_;
};

}  // namespace pf::test::farm
