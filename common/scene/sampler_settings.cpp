#include "scene/sampler_settings.h"

#include <bit>

#include "scene/plugins.h"

namespace pf {

namespace {

// Far beyond any useful per-pixel count, and small enough that sampleCount * pixels cannot overflow
// the 64-bit sample indices of the render loops.
constexpr int64_t kMaxSampleCount = int64_t(1) << 24;

int64_t readSampleCount(const Properties &props) {
    const int64_t n = props.getInt("sampleCount", 4);
    if (n < 1 || n > kMaxSampleCount)
        props.fail("sampleCount", "must lie in [1, " + std::to_string(kMaxSampleCount) + "]");
    return n;
}

// Mitsuba's "dimension" parameter (stratified, ldsampler) sets how many dimensions get stratified
// samples; it has no effect on independent sampling but is still validated.
void readDimension(const Properties &props) {
    if (props.getInt("dimension", 4) < 1) props.fail("dimension", "must be positive");
}

// Mitsuba's "scramble" parameter (halton, hammersley, sobol): -1 selects Mitsuba's default
// permutation, other values a seed. Accepted for compatibility only.
void readScramble(const Properties &props) { props.getInt("scramble", -1); }

std::shared_ptr<Object> makeSettings(int64_t sampleCount) {
    return std::make_shared<SamplerSettings>(static_cast<int>(sampleCount));
}

}  // namespace

PluginTable samplerPlugins() {
    return {
        {"independent",
         [](const Properties &props, const LoadContext &) { return makeSettings(readSampleCount(props)); }},
        // Mitsuba's stratified sampler rounds the count up to the next perfect square (one sample per
        // stratum of a square grid); we keep its sample count so that spp match Mitsuba's renders.
        {"stratified",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             readDimension(props);
             int64_t res = 1;
             while (res * res < n) ++res;
             return makeSettings(res * res);
         }},
        // Mitsuba's ldsampler (Kollig and Keller's (0,2)-sequence) rounds up to a power of two.
        {"ldsampler",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             readDimension(props);
             return makeSettings(static_cast<int64_t>(std::bit_ceil(static_cast<uint64_t>(n))));
         }},
        {"halton",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             readScramble(props);
             return makeSettings(n);
         }},
        {"hammersley",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             readScramble(props);
             return makeSettings(n);
         }},
        {"sobol",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             readScramble(props);
             return makeSettings(n);
         }},
    };
}

}  // namespace pf
