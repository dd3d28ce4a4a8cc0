// The client side of the farm protocol, shared by the farm commands (submit, fetch, ...) and `pathfarm
// compare`: where the master is and how to authenticate, uploading scene bundles, building job specs
// and downloading images.
#pragma once
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

    std::string token() const;
    // A context carrying the token, with a deadline unless timeoutSeconds is 0.
    std::unique_ptr<grpc::ClientContext> context(int timeoutSeconds = 60) const;
    std::shared_ptr<grpc::Channel> channel() const;
};

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
// The final image of a finished job, or the running image of an unfinished one.
FetchedImage fetchImage(pathfarm::v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id);
// Writes bytes to `path`, creating its directory.
void writeBytes(const std::string &path, const std::string &bytes);

}  // namespace pf::client
