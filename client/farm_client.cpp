#include "farm_client.h"

#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

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

std::shared_ptr<grpc::Channel> FarmConnection::channel() const { return farm::makeChannel(master, tls, 64 << 20); }

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
    const auto ctx = farm.context(600);
    auto reader = stub.FetchImage(ctx.get(), req);
    v1::ImageChunk chunk;
    FetchedImage image;
    while (reader->Read(&chunk)) {
        if (chunk.has_info()) image.info = chunk.info();
        image.exr += chunk.data();
    }
    check(reader->Finish(), "fetching the image of job " + std::to_string(id));
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
