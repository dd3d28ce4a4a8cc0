// libFuzzer target: the master's decoding of what its gRPC services receive, without a server. The first
// byte picks the request:
//   0  a SubmitJobRequest, its spec checked against the master's limits (master/job_spec_check.h);
//   1+ a CompleteTask stream: length-prefixed ResultChunks (2 bytes, little-endian, then the message),
//      read as the service reads them (farm/result_stream.h), and the payload decoded as an image task's
//      block, a chain task's output and a seeding task's result on a 16 x 12 film, as Master::complete
//      decodes it.
// Bad input must end in a farm::FarmError (the services' INVALID_ARGUMENT).
#include "farm/block_codec.h"
#include "farm/chain_codec.h"
#include "farm/error.h"
#include "farm/hash.h"
#include "farm/result_stream.h"
#include "fuzz_util.h"
#include "job_spec_check.h"
#include "pathfarm/v1/client.pb.h"
#include "scene/scene.h"

namespace {

namespace v1 = pathfarm::v1;

// The film the payloads are decoded against: a tiny scene's.
const pf::Film &film() {
    static const std::unique_ptr<pf::Scene> scene = [] {
        const std::string xml = R"(<scene version="0.5.0"><sensor type="perspective"><film type="hdrfilm">
<integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
<shape type="sphere"><emitter type="area"><spectrum name="radiance" value="1"/></emitter></shape></scene>)";
        return pf::loadScene(
            pf::fuzz::writeInput("film.xml", reinterpret_cast<const uint8_t *>(xml.data()), xml.size()));
    }();
    return scene->sensor().film();
}

// As the master decodes them (master/merger.cpp): image results into dense blocks, chain results into tiles.
pf::ImageBlock emptyBlock(pf::BlockStorage storage = pf::BlockStorage::Dense) {
    const pf::Film &f = film();
    return pf::ImageBlock(0, 0, f.cropWidth(), f.cropHeight(), &f.filter(), storage);
}

void completeTask(const uint8_t *data, size_t size) {
    pf::fuzz::FrameReader frames(data, size);
    const auto read = [&](v1::ResultChunk &chunk) { return frames(chunk); };
    const v1::ResultHeader header = pf::farm::readResultHeader(read);
    const std::string payload = pf::farm::readResultPayload(header, 1 << 20, read);
    const auto attempt = [&](auto decode) {
        try {
            decode();
        } catch (const pf::farm::FarmError &) {
        }
    };
    attempt([&] {
        pf::ImageBlock block = emptyBlock();
        pf::farm::decodeBlock(payload, block);
    });
    attempt([&] { pf::farm::decodeChainResult(payload, emptyBlock(pf::BlockStorage::Tiles)); });
    attempt([&] {
        const pf::SeedingTask task{0, static_cast<uint64_t>(film().cropWidth() * film().cropHeight()), 0};
        pf::farm::decodeSeedingResult(payload, film(), task);
    });
}

// A valid request of each kind.
std::vector<std::string> seeds() {
    v1::SubmitJobRequest submit;
    v1::JobSpec &spec = *submit.mutable_spec();
    spec.set_bundle_hash(std::string(32, 'a'));
    spec.set_integrator("path");
    spec.mutable_budget()->set_spp(16);
    auto *p = spec.add_params();
    p->set_name("maxDepth");
    p->set_value("5");
    std::vector<std::string> out = {std::string(1, '\0') + submit.SerializeAsString()};
    const auto stream = [](const std::string &payload) {
        v1::ResultChunk header, data;
        header.mutable_header()->set_attempt_id(1);
        header.mutable_header()->set_payload_size(payload.size());
        header.mutable_header()->set_payload_hash(pf::farm::hashHex64(payload));
        data.set_data(payload);
        return "\1" + pf::fuzz::frame(header) + pf::fuzz::frame(data);
    };
    out.push_back(stream(pf::farm::encodeBlock(emptyBlock())));
    pf::SeedingResult seeding;
    seeding.depthLuminance = {0.5, 0.25};
    seeding.samples = 192;
    out.push_back(stream(pf::farm::encodeSeedingResult(seeding)));
    // A chain result whose film holds two tiles (deposits in two corners of the 16 x 12 film).
    pf::ChainResult chain{emptyBlock(pf::BlockStorage::Tiles), 100, 0, {}, {}, 0, 0};
    chain.film.splat({0.5, 0.5}, pf::Spectrum(1.0));
    chain.film.splat({15.5, 11.5}, pf::Spectrum(2.0));
    out.push_back(stream(pf::farm::encodeChainResult(chain)));
    return out;
}

}  // namespace

PATHFARM_FUZZ_SEEDS(seeds)

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    try {
        if (data[0] == 0) {
            v1::SubmitJobRequest req;
            if (req.ParseFromArray(data + 1, static_cast<int>(size - 1)))
                pf::master::checkJobSpec(req.spec(), pf::master::MasterConfig{});
        } else {
            completeTask(data + 1, size - 1);
        }
    } catch (const pf::farm::FarmError &) {
    }
    return 0;
}
