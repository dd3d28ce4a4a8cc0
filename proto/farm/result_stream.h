// A task result as the master's CompleteTask service receives it: a ResultHeader chunk, then data chunks
// that must add up to exactly the announced size and hash. Split from the service so that the decoding
// of what arrives on the wire can be fuzzed without a server (fuzz/fuzz_master_requests.cpp).
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "pathfarm/v1/worker.pb.h"

namespace pf::farm {

// The stream's header: the first chunk, which must carry one. Throws FarmError otherwise (`read` returns
// false at the end of the stream).
pathfarm::v1::ResultHeader readResultHeader(const std::function<bool(pathfarm::v1::ResultChunk &)> &read);

// The payload that follows the header: refused (FarmError) when the header announces more than
// `maxBytes`, when data chunks exceed or fall short of the announced size, or when the payload does not
// match its hash. A payload in one chunk is taken over rather than copied.
std::string readResultPayload(const pathfarm::v1::ResultHeader &header, uint64_t maxBytes,
                              const std::function<bool(pathfarm::v1::ResultChunk &)> &read);

}  // namespace pf::farm
