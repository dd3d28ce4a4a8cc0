// Content hashes of the farm (XXH3): of bundle files and result payloads (64 bits) and of whole bundles
// (128 bits), written as lowercase hex.
#pragma once
#include <xxhash.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace pf::farm {

std::string hashHex64(std::string_view data);

// Incremental XXH3-64, for data that arrives in chunks.
class Hasher64 {
public:
    Hasher64();
    ~Hasher64();
    Hasher64(const Hasher64 &) = delete;
    Hasher64 &operator=(const Hasher64 &) = delete;
    void update(std::string_view data);
    std::string hex() const;

private:
    XXH3_state_t *state_;
};

std::string hashHex128(std::string_view data);

}  // namespace pf::farm
