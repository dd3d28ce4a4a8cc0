// Helpers for tests of Markov-chain tasks (render/chain.h): the seeding a job starts from, and a chain
// task's result as bytes, to compare runs bit for bit (in this process or in child processes).
#pragma once
#include <cstdint>
#include <string>

#include "render/chain.h"
#include "render/normalizer.h"

namespace pf::test {

// Runs every seeding task of `integrator` on `scene` (with its default seeding) and sums them up.
Normalizer seedChains(const Scene &scene, const ChainIntegrator &integrator, uint64_t seed);

// The film's splat tiles, the mutation count and the per-type counts of a chain task's result, byte for byte.
std::string chainResultBytes(const ChainResult &result);

// This test executable's own path, to run one of its tests in a child process.
std::string selfPath();

// The contents of a file ("" if it cannot be read).
std::string readFile(const std::string &path);

}  // namespace pf::test
