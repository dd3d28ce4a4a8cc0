#include "farm/block_codec.h"

#include <zstd.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <bit>
#include <cmath>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "farm/error.h"

namespace pf::farm {

namespace {

constexpr char kMagic[4] = {'P', 'F', 'B', '1'};

struct Header {
    char magic[4];
    int32_t offsetX, offsetY, width, height, border;
    uint64_t invalidSamples;
    uint64_t values;  // doubles in the three arrays together
};
static_assert(std::endian::native == std::endian::little, "the block encoding is little-endian");

// Values [first, first + count) of `values` byte-shuffled doubles back into `out`: byte b of value i is
// shuffled[b * values + i] (little-endian). The master decodes every result through this, so sixteen
// values at a time go through an 8 x 16 byte transpose in three rounds of SSE2 unpacks (bytes, byte
// pairs, byte quads); the rest byte by byte.
void unshuffle(const unsigned char *shuffled, size_t values, size_t first, size_t count, double *out) {
    const unsigned char *plane[sizeof(double)];
    for (size_t b = 0; b < sizeof(double); ++b) plane[b] = shuffled + b * values + first;
    size_t i = 0;
#ifdef __SSE2__
    for (; i + 16 <= count; i += 16) {
        __m128i a[8];
        for (int b = 0; b < 8; ++b) a[b] = _mm_loadu_si128(reinterpret_cast<const __m128i *>(plane[b] + i));
        __m128i pairs[8], quads[8];
        for (int b = 0; b < 4; ++b) {
            pairs[2 * b] = _mm_unpacklo_epi8(a[2 * b], a[2 * b + 1]);      // values 0-7, bytes 2b and 2b+1
            pairs[2 * b + 1] = _mm_unpackhi_epi8(a[2 * b], a[2 * b + 1]);  // values 8-15
        }
        for (int h = 0; h < 2; ++h)
            for (int g = 0; g < 2; ++g) {  // bytes 0-3 (g = 0) and 4-7 (g = 1) of values 8h .. 8h+7
                quads[4 * h + 2 * g] = _mm_unpacklo_epi16(pairs[4 * g + h], pairs[4 * g + 2 + h]);
                quads[4 * h + 2 * g + 1] = _mm_unpackhi_epi16(pairs[4 * g + h], pairs[4 * g + 2 + h]);
            }
        auto *dst = reinterpret_cast<__m128i *>(out + i);
        for (int q = 0; q < 4; ++q) {  // values 4q .. 4q+3: their bytes 0-3 and 4-7, interleaved
            const __m128i lo = quads[4 * (q / 2) + (q % 2)], hi = quads[4 * (q / 2) + 2 + (q % 2)];
            _mm_storeu_si128(dst + 2 * q, _mm_unpacklo_epi32(lo, hi));
            _mm_storeu_si128(dst + 2 * q + 1, _mm_unpackhi_epi32(lo, hi));
        }
    }
#endif
    for (; i < count; ++i) {
        unsigned char bytes[sizeof(double)];
        for (size_t b = 0; b < sizeof(double); ++b) bytes[b] = plane[b][i];
        std::memcpy(out + i, bytes, sizeof(double));
    }
}

std::string layout(int ox, int oy, int w, int h, int border) {
    return std::to_string(w) + "x" + std::to_string(h) + " at (" + std::to_string(ox) + ", " + std::to_string(oy) +
           ") with border " + std::to_string(border);
}

}  // namespace

std::string encodeBlock(const ImageBlock &block, int zstdLevel) {
    const std::span<const double> arrays[] = {block.sumData(), block.weightData(), block.splatData()};
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    std::vector<unsigned char> shuffled(values * sizeof(double));
    size_t i = 0;
    for (const auto &a : arrays)
        for (const double v : a) {
            unsigned char bytes[sizeof(double)];
            std::memcpy(bytes, &v, sizeof v);
            for (size_t b = 0; b < sizeof(double); ++b) shuffled[b * values + i] = bytes[b];
            ++i;
        }

    const Header h{{kMagic[0], kMagic[1], kMagic[2], kMagic[3]},
                   block.offsetX(),
                   block.offsetY(),
                   block.width(),
                   block.height(),
                   block.border(),
                   block.invalidSamples(),
                   values};
    std::string out(sizeof h + ZSTD_compressBound(shuffled.size()), '\0');
    std::memcpy(out.data(), &h, sizeof h);
    // With a content checksum, so that a block damaged at rest (a result file, a checkpoint) is refused
    // rather than merged.
    const std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx *)> cctx(ZSTD_createCCtx(), ZSTD_freeCCtx);
    if (!cctx) throw std::bad_alloc();
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, zstdLevel);
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 1);
    const size_t n =
        ZSTD_compress2(cctx.get(), out.data() + sizeof h, out.size() - sizeof h, shuffled.data(), shuffled.size());
    if (ZSTD_isError(n)) throw FarmError(std::string("block compression failed: ") + ZSTD_getErrorName(n));
    out.resize(sizeof h + n);
    return out;
}

void decodeBlock(std::string_view data, ImageBlock &block) {
    std::vector<unsigned char> scratch;
    decodeBlock(data, block, scratch);
}

void decodeBlock(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch) {
    Header h;
    if (data.size() < sizeof h) throw FarmError("film block: truncated header");
    std::memcpy(&h, data.data(), sizeof h);
    if (std::memcmp(h.magic, kMagic, sizeof kMagic) != 0) throw FarmError("film block: not a pathfarm block");
    if (h.offsetX != block.offsetX() || h.offsetY != block.offsetY() || h.width != block.width() ||
        h.height != block.height() || h.border != block.border())
        throw FarmError("film block: layout " + layout(h.offsetX, h.offsetY, h.width, h.height, h.border) +
                        ", expected " +
                        layout(block.offsetX(), block.offsetY(), block.width(), block.height(), block.border()));
    const std::span<double> arrays[] = {block.sumData(), block.weightData(), block.splatData()};
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    if (h.values != values) throw FarmError("film block: wrong number of values");

    const std::string_view compressed = data.substr(sizeof h);
    const unsigned long long content = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
    if (content != values * sizeof(double)) throw FarmError("film block: corrupt or truncated data");
    if (scratch.size() < values * sizeof(double)) scratch.resize(values * sizeof(double));
    const unsigned char *shuffled = scratch.data();
    const size_t n = ZSTD_decompress(scratch.data(), values * sizeof(double), compressed.data(), compressed.size());
    if (ZSTD_isError(n) || n != values * sizeof(double))
        throw FarmError(std::string("film block: ") + (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short data"));

    size_t first = 0;
    for (const auto &a : arrays) {
        unshuffle(shuffled, values, first, a.size(), a.data());
        first += a.size();
        bool finite = true;
        for (const double v : a) finite &= std::isfinite(v);
        if (!finite) throw FarmError("film block: non-finite value");
    }
    block.setInvalidSamples(h.invalidSamples);
}

}  // namespace pf::farm
