// PCG32 (O'Neill 2014, pcg-random.org "pcg32" = XSH-RR 64/32) with selectable stream, as in
// Mitsuba 2 and pbrt-v3. Every random stream in the renderer is a pure function of
// (job seed, pixel or chain id, sample index), so results never depend on thread scheduling.
#pragma once
#include <cstdint>

namespace pf {

class PCG32 {
public:
    PCG32() { seed(0x853c49e6748fea9bULL, 0xda3e39cb94b95bdbULL); }
    PCG32(uint64_t initState, uint64_t stream) { seed(initState, stream); }

    void seed(uint64_t initState, uint64_t stream) {
        state_ = 0;
        inc_ = (stream << 1u) | 1u;
        nextUInt();
        state_ += initState;
        nextUInt();
    }
    uint32_t nextUInt() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31));
    }
    // Uniform in [0, 1) with 53 random bits.
    double nextDouble() {
        const uint64_t hi = nextUInt(), lo = nextUInt();
        return static_cast<double>(((hi << 32) | lo) >> 11) * 0x1.0p-53;
    }
    // Uniform integer in [0, bound).
    uint32_t nextUInt(uint32_t bound) {
        const uint32_t threshold = (~bound + 1u) % bound;
        for (;;) {
            const uint32_t r = nextUInt();
            if (r >= threshold) return r % bound;
        }
    }
    uint64_t state() const { return state_; }
    uint64_t inc() const { return inc_; }

private:
    uint64_t state_ = 0, inc_ = 0;
};

// 64-bit finalizer (splitmix64) used to derive independent seeds from tuples of integers.
inline uint64_t mix64(uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
inline uint64_t hashCombine(uint64_t a, uint64_t b) { return mix64(a ^ mix64(b)); }

}  // namespace pf
