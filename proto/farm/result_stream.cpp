#include "farm/result_stream.h"

#include "farm/error.h"
#include "farm/hash.h"

namespace pf::farm {

namespace v1 = pathfarm::v1;

v1::ResultHeader readResultHeader(const std::function<bool(v1::ResultChunk &)> &read) {
    v1::ResultChunk chunk;
    if (!read(chunk) || !chunk.has_header()) throw FarmError("CompleteTask: the stream must start with a ResultHeader");
    return chunk.header();
}

std::string readResultPayload(const v1::ResultHeader &header, uint64_t maxBytes,
                              const std::function<bool(v1::ResultChunk &)> &read) {
    if (header.payload_size() > maxBytes)
        throw FarmError("CompleteTask: a payload of " + std::to_string(header.payload_size()) +
                        " bytes is larger than this task's film can be");
    std::string payload;
    v1::ResultChunk chunk;
    while (read(chunk)) {
        if (!chunk.has_data() || payload.size() + chunk.data().size() > header.payload_size())
            throw FarmError("CompleteTask: more data than the header announced");
        if (payload.empty()) {
            payload.swap(*chunk.mutable_data());
            payload.reserve(header.payload_size());
        } else {
            payload += chunk.data();
        }
    }
    if (payload.size() != header.payload_size())
        throw FarmError("CompleteTask: the payload ended early (" + std::to_string(payload.size()) + " of " +
                        std::to_string(header.payload_size()) + " bytes)");
    if (hashHex64(payload) != header.payload_hash())
        throw FarmError("CompleteTask: the payload does not match its hash");
    return payload;
}

}  // namespace pf::farm
