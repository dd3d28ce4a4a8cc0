#include "farm_job.h"

#include <chrono>
#include <thread>

#include "farm/convert.h"

namespace pf::client {

namespace v1 = pathfarm::v1;

namespace {

v1::Job getJob(v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id) {
    v1::GetJobRequest req;
    req.set_id(id);
    v1::Job job;
    callReconnecting(farm, "job " + std::to_string(id), [&] { return stub.GetJob(farm.context().get(), req, &job); });
    return job;
}

// Follows the job to its end, taking the snapshots.
v1::Job follow(v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id, const JobObserver &observer) {
    // Polling is cheap (one small message); 20 ms keeps a snapshot within a few percent of its time
    // for budgets of a second and more.
    constexpr auto kPoll = std::chrono::milliseconds(20);
    const std::vector<double> &times = observer.snapshotTimes;
    size_t next = 0;
    v1::Job job;
    while (!jobEnded(job = getJob(stub, farm, id))) {
        if (next < times.size() && job.state() == v1::JOB_RUNNING && job.render_seconds() >= times[next]) {
            JobSnapshot s;
            try {
                s.image = fetchImage(stub, farm, id);
            } catch (const CallError &e) {
                // Nothing merged yet: the snapshot waits for the first merge.
                if (e.code != grpc::StatusCode::FAILED_PRECONDITION) throw;
                std::this_thread::sleep_for(kPoll);
                continue;
            }
            // The time after the fetch: the image holds at most what was merged by then.
            const v1::Job after = getJob(stub, farm, id);
            s.seconds = after.state() == v1::JOB_RUNNING ? after.render_seconds() : job.render_seconds();
            if (s.image.info.samples_per_pixel() > 0 && !s.image.info.final() && observer.snapshot)
                observer.snapshot(s);
            while (next < times.size() && times[next] <= s.seconds) ++next;
            continue;
        }
        std::this_thread::sleep_for(kPoll);
    }
    return job;
}

}  // namespace

FinishedJob runJob(v1::ClientService::Stub &stub, const FarmConnection &farm, const v1::JobSpec &spec,
                   const JobObserver &observer) {
    v1::SubmitJobRequest req;
    *req.mutable_spec() = spec;
    v1::Job job;
    check(stub.SubmitJob(farm.context().get(), req, &job), "submitting " + spec.label());
    try {
        if (observer.submitted) observer.submitted(job);
        job = follow(stub, farm, job.id(), observer);
    } catch (...) {
        v1::CancelJobRequest cancel;
        cancel.set_id(job.id());
        v1::Job ignored;
        (void)stub.CancelJob(farm.context(10).get(), cancel, &ignored);
        throw;
    }
    if (job.state() != v1::JOB_DONE)
        throw std::runtime_error("job " + std::to_string(job.id()) + " (" + spec.label() + ") " +
                                 farm::stateName(job.state()) + (job.error().empty() ? "" : ": " + job.error()));
    return {job, fetchImage(stub, farm, job.id())};
}

}  // namespace pf::client
