// The Markov-chain tasks and their results on the wire (ARCHITECTURE.md "A job, end to end"): chain
// tasks carry their starts as compact path records (render/seeding.h), seeding results their candidate
// records and luminance sums, chain results an encoded film block with the chains' statistics. Every
// double travels as its exact bits, so a result merged on the master is the result the worker computed.
#pragma once
#include <string>
#include <string_view>

#include "pathfarm/v1/common.pb.h"
#include "render/chain.h"
#include "render/normalizer.h"
#include "render/seeding.h"

namespace pf::farm {

pathfarm::v1::ChainTask toProto(const ChainTask &task);
// Throws FarmError when the task is malformed (columns of unequal length, weights not finite).
ChainTask fromProto(const pathfarm::v1::ChainTask &task);

// Seeding tasks (the pilot of a burst job included).
void toProto(const SeedingTask &task, pathfarm::v1::SeedingTask &out);
SeedingTask fromProto(const pathfarm::v1::SeedingTask &task);

std::string encodeSeedingResult(const SeedingResult &result);
// Throws FarmError naming the problem when the payload is corrupt, or when a candidate lies outside
// `task`'s pixels of `film` or has a weight that is negative or not finite.
SeedingResult decodeSeedingResult(std::string_view payload, const Film &film, const SeedingTask &task);

// Chain results, and the merged chains of a checkpoint (ChainImage has the same figures).
pathfarm::v1::ChainOutput toProto(const ChainImage &chains);
std::string encodeChainResult(const ChainResult &result);
// Decodes into `film`, which must have the layout of the job's film (see decodeBlock).
ChainResult decodeChainResult(std::string_view payload, ImageBlock film);
ChainImage fromProto(const pathfarm::v1::ChainOutput &chains, ImageBlock film);

// Mutation counts and counters as the Job message shows them (acceptance filled in).
void toProto(const MutationCounts &counts, google::protobuf::RepeatedPtrField<pathfarm::v1::MutationCount> &out);
void toProto(const ChainCounters &counters, google::protobuf::RepeatedPtrField<pathfarm::v1::ChainCounter> &out);

}  // namespace pf::farm
