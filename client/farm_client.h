// The client side of the farm protocol, shared by the farm commands (submit, fetch, ...) and `pathfarm
// compare`: where the master is and how to authenticate, uploading scene bundles, building job specs
// and downloading images.
#pragma once
#include <chrono>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "farm/job_setup.h"
#include "farm/rpc.h"
#include "pathfarm/v1/client.grpc.pb.h"

namespace pf::client {

// A failed call: its status becomes the message and the exit code.
struct CallError : std::runtime_error {
    CallError(const std::string &what, const grpc::Status &s)
        : std::runtime_error(what + ": " + s.error_message()), code(s.error_code()) {}
    grpc::StatusCode code;
};

// Throws CallError for a failed status.
void check(const grpc::Status &s, const std::string &what);

// A master and the credentials to talk to it: the client token from `tokenFile` or PATHFARM_TOKEN.
struct FarmConnection {
    std::string master, tokenFile;
    farm::TlsFiles tls;
    // How long the calls that reconnect (see Reconnector) keep trying a master that has become
    // unreachable, in seconds; 0: they fail at once.
    int reconnectSeconds = 0;

    std::string token() const;
    // A context carrying the token, with a deadline unless timeoutSeconds is 0.
    std::unique_ptr<grpc::ClientContext> context(int timeoutSeconds = 60) const;
    // The channel to the master, made from the fields above on the first call and then shared by every
    // stub made from it (and by the copies of this connection), so that reconnecting can hurry it.
    std::shared_ptr<grpc::Channel> channel() const;

private:
    mutable std::shared_ptr<grpc::Channel> channel_;
};

// Rides out a master restart or a dropped connection for a call that is safe to repeat, made through a
// stub of farm.channel(): after a failed attempt, `failed` waits for the channel to connect again (up to
// a backoff doubling from 0.25 s to 2 s) when the failure means the master is unreachable and the
// connection's reconnectSeconds have not passed since the master last answered, and throws CallError
// otherwise. An unknown job, a refused token or a bad request fail the same way however often they are
// tried, so they throw at once. The first wait of an outage says so on stderr, and so does the answer
// that ends it.
class Reconnector {
public:
    Reconnector(const FarmConnection &farm, std::string what);
    // The master answered: a later failure starts a new outage, with the full time and a fresh backoff.
    void reached();
    void failed(const grpc::Status &s);

private:
    using Clock = std::chrono::steady_clock;
    const FarmConnection &farm_;
    std::string what_;
    Clock::time_point outageStart_;
    Clock::duration backoff_{};
    bool inOutage_ = false;
};

// Done, failed or cancelled.
bool jobEnded(const pathfarm::v1::Job &j);

// Runs `attempt` until it succeeds, through a Reconnector.
void callReconnecting(const FarmConnection &farm, const std::string &what,
                      const std::function<grpc::Status()> &attempt);

// A scene as the farm knows it: the manifest of its bundle and the bundle's content hash.
struct SceneBundle {
    pathfarm::v1::BundleManifest manifest;
    std::string hash, dir, sceneFile;
};
// Collects the files of `scenePath` (with `defines` substituted); SceneError if the scene is missing.
SceneBundle makeSceneBundle(const std::string &scenePath, const NameValues &defines);
// Uploads the bundle unless the master stores it already (bundles are content-addressed).
void uploadBundle(pathfarm::v1::ClientService::Stub &stub, const FarmConnection &farm, const SceneBundle &bundle);

// The master's warnings about a submitted job's scene (unused parameters), on stderr as `pathfarm render`
// prints its own: "warning: scene.xml:17: perspective: unused parameter 'focusDistance'".
void printWarnings(const pathfarm::v1::Job &job);

// The parameters or definitions of a job spec.
void setParams(google::protobuf::RepeatedPtrField<pathfarm::v1::Param> &out, const NameValues &values);

// A job's image as the master serves it: the EXR file's bytes and what they hold.
struct FetchedImage {
    pathfarm::v1::ImageInfo info;
    std::string exr;
};
// The final image of a finished job, or the running image of an unfinished one; a download cut off by
// the master's restart starts again (within farm.reconnectSeconds).
FetchedImage fetchImage(pathfarm::v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id);
// Writes bytes to `path`, creating its directory.
void writeBytes(const std::string &path, const std::string &bytes);

}  // namespace pf::client
