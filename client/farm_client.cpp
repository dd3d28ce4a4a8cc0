#include "farm_client.h"

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "core/error.h"
#include "farm/bundle.h"

namespace pf::client {

namespace fs = std::filesystem;
namespace v1 = pathfarm::v1;

void check(const grpc::Status &s, const std::string &what) {
    if (!s.ok()) throw CallError(what, s);
}

std::string FarmConnection::token() const {
    if (!tokenFile.empty()) return farm::readToken(tokenFile);
    if (const char *t = std::getenv("PATHFARM_TOKEN"); t && *t) return t;
    throw std::runtime_error("no client token: give --token-file or set PATHFARM_TOKEN");
}

std::unique_ptr<grpc::ClientContext> FarmConnection::context(int timeoutSeconds) const {
    auto ctx = std::make_unique<grpc::ClientContext>();
    farm::setBearer(*ctx, token());
    if (timeoutSeconds > 0) ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(timeoutSeconds));
    return ctx;
}

std::shared_ptr<grpc::Channel> FarmConnection::channel() const {
    if (!channel_) channel_ = farm::makeChannel(master, tls, 64 << 20);
    return channel_;
}

namespace {

// UNAVAILABLE: no connection, or the connection broke (master killed, restarted, network cut).
// CANCELLED: these calls are never cancelled by the client, so the master cancelled them (shutdown).
bool masterUnreachable(grpc::StatusCode code) {
    return code == grpc::StatusCode::UNAVAILABLE || code == grpc::StatusCode::CANCELLED;
}

}  // namespace

Reconnector::Reconnector(const FarmConnection &farm, std::string what) : farm_(farm), what_(std::move(what)) {}

void Reconnector::reached() {
    if (!inOutage_) return;
    inOutage_ = false;
    const double seconds = std::chrono::duration<double>(Clock::now() - outageStart_).count();
    std::fprintf(stderr, "reconnected to %s after %.1f s\n", farm_.master.c_str(), seconds);
}

void Reconnector::failed(const grpc::Status &s) {
    if (farm_.reconnectSeconds <= 0 || !masterUnreachable(s.error_code())) throw CallError(what_, s);
    const Clock::time_point now = Clock::now();
    if (!inOutage_) {
        inOutage_ = true;
        outageStart_ = now;
        // A restarted master listens again within a second or two; the cap keeps a long outage from
        // being noticed late.
        backoff_ = std::chrono::milliseconds(250);
        std::fprintf(stderr, "master %s unreachable (%s); reconnecting for up to %d s\n", farm_.master.c_str(),
                     s.error_message().c_str(), farm_.reconnectSeconds);
    }
    const Clock::time_point giveUp = outageStart_ + std::chrono::seconds(farm_.reconnectSeconds);
    if (now >= giveUp)
        throw CallError(what_, grpc::Status(s.error_code(), "master still unreachable after " +
                                                                std::to_string(farm_.reconnectSeconds) +
                                                                " s: " + s.error_message()));
    // Until the channel has connected again every call fails at once, so the wait is spent connecting.
    // gRPC's own backoff between connection attempts has grown while the master was away: reset, it
    // tries now. Waiting for the connection (rather than sleeping) also drives the channel: with no call
    // under way, gRPC would see a connection attempt's outcome only every 5 s (its backup poller).
    const Clock::duration wait = std::min<Clock::duration>(backoff_, giveUp - now);
    const std::shared_ptr<grpc::Channel> channel = farm_.channel();
    grpc::experimental::ChannelResetConnectionBackoff(channel.get());
    // Connected at once (a master still shutting down may accept): a short pause all the same.
    if (channel->WaitForConnected(std::chrono::system_clock::now() + wait))
        std::this_thread::sleep_until(std::min(now + wait, now + std::chrono::milliseconds(250)));
    backoff_ = std::min<Clock::duration>(2 * backoff_, std::chrono::seconds(2));
}

bool jobEnded(const v1::Job &j) {
    return j.state() == v1::JOB_DONE || j.state() == v1::JOB_FAILED || j.state() == v1::JOB_CANCELLED;
}

void callReconnecting(const FarmConnection &farm, const std::string &what,
                      const std::function<grpc::Status()> &attempt) {
    Reconnector reconnect(farm, what);
    for (grpc::Status s; !(s = attempt()).ok();) reconnect.failed(s);
    reconnect.reached();
}

SceneBundle makeSceneBundle(const std::string &scenePath, const NameValues &defines) {
    if (!fs::is_regular_file(scenePath)) throw SceneError(scenePath + ": no such scene file");
    const fs::path scene = fs::absolute(scenePath);
    SceneBundle b;
    b.dir = scene.parent_path().string();
    b.sceneFile = scene.filename().string();
    b.manifest = farm::makeManifest(b.dir, b.sceneFile, farm::collectSceneFiles(scene.string(), defines));
    b.hash = farm::bundleHash(b.manifest);
    return b;
}

void uploadBundle(v1::ClientService::Stub &stub, const FarmConnection &farm, const SceneBundle &bundle) {
    v1::StatBundleRequest statReq;
    statReq.set_hash(bundle.hash);
    v1::StatBundleReply stat;
    check(stub.StatBundle(farm.context().get(), statReq, &stat), "contacting " + farm.master);
    if (stat.present()) return;
    v1::UploadBundleReply reply;
    const auto ctx = farm.context(3600);
    auto writer = stub.UploadBundle(ctx.get(), &reply);
    farm::streamBundle(bundle.dir, bundle.manifest, 1 << 20,
                       [&](const v1::BundleChunk &chunk) { return writer->Write(chunk); });
    writer->WritesDone();
    check(writer->Finish(), "uploading " + bundle.sceneFile);
    if (reply.hash() != bundle.hash) throw std::runtime_error("the master stored the bundle as " + reply.hash());
    std::fprintf(stderr, "uploaded %d files (%" PRIu64 " bytes) as bundle %s\n", bundle.manifest.entries_size(),
                 reply.bytes(), bundle.hash.c_str());
}

void printWarnings(const v1::Job &job) {
    for (const std::string &w : job.warnings()) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

void setParams(google::protobuf::RepeatedPtrField<v1::Param> &out, const NameValues &values) {
    for (const auto &[n, v] : values) {
        v1::Param *p = out.Add();
        p->set_name(n);
        p->set_value(v);
    }
}

FetchedImage fetchImage(v1::ClientService::Stub &stub, const FarmConnection &farm, int64_t id) {
    v1::FetchImageRequest req;
    req.set_id(id);
    FetchedImage image;
    callReconnecting(farm, "fetching the image of job " + std::to_string(id), [&] {
        const auto ctx = farm.context(600);
        auto reader = stub.FetchImage(ctx.get(), req);
        v1::ImageChunk chunk;
        // A download cut off part way starts again from the first chunk.
        image = FetchedImage();
        while (reader->Read(&chunk)) {
            if (chunk.has_info()) image.info = chunk.info();
            image.exr += chunk.data();
        }
        return reader->Finish();
    });
    if (image.exr.size() != image.info.size())
        throw std::runtime_error("the image of job " + std::to_string(id) + " arrived short");
    return image;
}

void writeBytes(const std::string &path, const std::string &bytes) {
    const fs::path out(path);
    if (out.has_parent_path()) fs::create_directories(out.parent_path());
    std::ofstream f(out, std::ios::binary);
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!f) throw std::runtime_error("cannot write " + path);
}

}  // namespace pf::client
