#include "farm/hash.h"

#include <cstdio>
#include <new>

namespace pf::farm {

namespace {

std::string hex(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

}  // namespace

std::string hashHex64(std::string_view data) { return hex(XXH3_64bits(data.data(), data.size())); }

Hasher64::Hasher64() : state_(XXH3_createState()) {
    if (!state_) throw std::bad_alloc();
    XXH3_64bits_reset(state_);
}

Hasher64::~Hasher64() { XXH3_freeState(state_); }

void Hasher64::update(std::string_view data) { XXH3_64bits_update(state_, data.data(), data.size()); }

std::string Hasher64::hex() const { return farm::hex(XXH3_64bits_digest(state_)); }

std::string hashHex128(std::string_view data) {
    const XXH128_hash_t h = XXH3_128bits(data.data(), data.size());
    return hex(h.high64) + hex(h.low64);
}

}  // namespace pf::farm
