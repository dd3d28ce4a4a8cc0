// One job on the farm from submission to its final image, with snapshots of the running image along
// the way: what `pathfarm compare` does for every run and for its reference.
#pragma once
#include <functional>
#include <vector>

#include "farm_client.h"

namespace pf::client {

// The running image at some point of a job: `seconds` is the job's rendering time (the master's clock,
// from its first lease) when the image had been fetched.
struct JobSnapshot {
    double seconds = 0;
    FetchedImage image;
};

struct FinishedJob {
    pathfarm::v1::Job job;  // the record as it ended (true render time, scene load times, counts)
    FetchedImage image;     // the final image
};

// What runJob reports along the way. `submitted` sees the accepted job first (its size, the integrator
// used) and may throw to abandon it; `snapshot` gets the running image once the job's rendering time has
// passed each of `snapshotTimes` (seconds, ascending), except snapshots that hold no samples yet.
struct JobObserver {
    std::vector<double> snapshotTimes;
    std::function<void(const pathfarm::v1::Job &)> submitted;
    std::function<void(const JobSnapshot &)> snapshot;
};

// Submits `spec` and waits for it to end. Throws CallError for a rejected job and std::runtime_error for
// a job that failed or was cancelled; a job abandoned by an exception is cancelled. Following the job
// and fetching its images ride out a master restart (farm.reconnectSeconds); the submission does not,
// since repeating it could submit the job twice.
FinishedJob runJob(pathfarm::v1::ClientService::Stub &stub, const FarmConnection &farm,
                   const pathfarm::v1::JobSpec &spec, const JobObserver &observer = {});

}  // namespace pf::client
