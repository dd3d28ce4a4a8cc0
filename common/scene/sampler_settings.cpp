#include "scene/sampler_settings.h"

#include <algorithm>
#include <bit>
#include <limits>

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

// Mitsuba's "dimension" parameter (stratified, ldsampler): how many 1D and how many 2D requests of a
// sample get stratified numbers (default 4); later ones draw independent numbers.
SampleSequence readDimension(const Properties &props) {
    const int64_t dimension = props.getInt("dimension", 4);
    if (dimension < 1) props.fail("dimension", "must be positive");
    return {true, static_cast<int>(std::min<int64_t>(dimension, std::numeric_limits<int>::max()))};
}

// Mitsuba's "scramble" parameter (halton, hammersley, sobol): -1 selects Mitsuba's default
// permutation, other values a seed. pathfarm's sequences are scrambled by the render's seed instead, so
// the value is read (a non-integer is an error) and has no effect.
SampleSequence readScramble(const Properties &props) {
    props.getInt("scramble", -1);
    return {true, 0};
}

// pathfarm's "layout" parameter of `sobol`: "pixel" (the default) gives each pixel its own padded sequence
// (core/ld_sampler.h), "image" one Sobol sequence through the whole image, as Mitsuba 0.6's `sobol` draws
// (core/global_sobol_sampler.h, which says what each is better at).
SampleSequence readSobolLayout(const Properties &props) {
    SampleSequence sequence = readScramble(props);
    const std::string layout = props.getString("layout", "pixel");
    if (layout != "pixel" && layout != "image") props.fail("layout", "must be \"pixel\" or \"image\"");
    sequence.acrossPixels = layout == "image";
    return sequence;
}

std::shared_ptr<Object> makeSettings(int64_t sampleCount, SampleSequence sequence) {
    return std::make_shared<SamplerSettings>(static_cast<int>(sampleCount), sequence);
}

}  // namespace

PluginTable samplerPlugins() {
    // Mitsuba's halton, hammersley and sobol keep their sample count and take the padded sequence; `sobol` can take
    // the global one instead (its `layout`).
    const auto scrambledSequence = [](const Properties &props, const LoadContext &) {
        const int64_t n = readSampleCount(props);
        return makeSettings(n, readScramble(props));
    };
    return {
        {"independent",
         [](const Properties &props, const LoadContext &) { return makeSettings(readSampleCount(props), {}); }},
        // Mitsuba's stratified sampler rounds the count up to the next perfect square (one sample per
        // stratum of a square grid); we keep its sample count so that spp match Mitsuba's renders.
        {"stratified",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             int64_t res = 1;
             while (res * res < n) ++res;
             return makeSettings(res * res, readDimension(props));
         }},
        // Mitsuba's ldsampler (Kollig and Keller's (0,2)-sequence) rounds up to a power of two.
        {"ldsampler",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             return makeSettings(static_cast<int64_t>(std::bit_ceil(static_cast<uint64_t>(n))), readDimension(props));
         }},
        {"halton", scrambledSequence},
        {"hammersley", scrambledSequence},
        {"sobol",
         [](const Properties &props, const LoadContext &) {
             const int64_t n = readSampleCount(props);
             return makeSettings(n, readSobolLayout(props));
         }},
    };
}

}  // namespace pf
