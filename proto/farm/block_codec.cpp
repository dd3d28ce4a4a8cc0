#include "farm/block_codec.h"

#include <zstd.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#include "farm/error.h"

namespace pf::farm {

namespace {

// The magic's last character is the body's layout (BodyLayout, below): blocks are written in layout 2, and
// layout 1 is still read, so that a master updated in the middle of a job reads the checkpoints and results
// that it or its workers wrote before.
constexpr char kMagic[4] = {'P', 'F', 'B', '2'}, kTileMagic[4] = {'P', 'F', 'T', '2'};

// A Dense block: the header, then its three arrays compressed.
struct Header {
    char magic[4];
    int32_t offsetX, offsetY, width, height, border;
    uint64_t invalidSamples;
    uint64_t values;  // doubles in the three arrays together
};
// A Tiles block (image/splat_tiles.h): the header, `tiles` uint32 indices of the tiles present in ascending
// order (the storage grid's tiles row by row), then those tiles' values in that order, compressed. The
// list is the block's whole shape, so the decoder knows how many values to expect before decompressing.
struct TileHeader {
    char magic[4];
    int32_t offsetX, offsetY, width, height, border;
    uint32_t tileSize, tiles;
    uint64_t invalidSamples;
};
static_assert(sizeof(Header) == 40 && sizeof(TileHeader) == 40, "headers without padding bytes");
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

template <class H>
void checkLayout(const H &h, const ImageBlock &block) {
    if (h.offsetX != block.offsetX() || h.offsetY != block.offsetY() || h.width != block.width() ||
        h.height != block.height() || h.border != block.border())
        throw FarmError("film block: layout " + layout(h.offsetX, h.offsetY, h.width, h.height, h.border) +
                        ", expected " +
                        layout(block.offsetX(), block.offsetY(), block.width(), block.height(), block.border()));
}

// Byte-shuffles values [first, first + count) of a sequence of `values` doubles: byte b of value i goes to
// shuffled[b * values + i] (little-endian), unshuffle's inverse. Workers encode every result through this (at
// 1024², a Markov-chain task's film is millions of doubles), so eight values at a time go through an 8 x 8 byte
// transpose of 64-bit words in three rounds of masked swaps, and each plane gets one 8-byte store; the rest
// byte by byte.
void shuffle(const double *in, size_t count, size_t values, size_t first, unsigned char *shuffled) {
    unsigned char *plane[sizeof(double)];
    for (size_t b = 0; b < sizeof(double); ++b) plane[b] = shuffled + b * values + first;
    size_t i = 0;
    for (; i + 8 <= count; i += 8) {
        uint64_t r[8];
        std::memcpy(r, in + i, sizeof r);
        // Swap the odd bytes of words 2k with the even bytes of words 2k+1, then byte pairs between words k and
        // k+2, then quads between k and k+4: word j ends up holding byte j of the eight words, word i's at byte i.
        for (int k = 0; k < 8; k += 2) {
            const uint64_t t = ((r[k] >> 8) ^ r[k + 1]) & 0x00FF00FF00FF00FFull;
            r[k + 1] ^= t;
            r[k] ^= t << 8;
        }
        for (const int k : {0, 1, 4, 5}) {
            const uint64_t t = ((r[k] >> 16) ^ r[k + 2]) & 0x0000FFFF0000FFFFull;
            r[k + 2] ^= t;
            r[k] ^= t << 16;
        }
        for (int k = 0; k < 4; ++k) {
            const uint64_t t = ((r[k] >> 32) ^ r[k + 4]) & 0x00000000FFFFFFFFull;
            r[k + 4] ^= t;
            r[k] ^= t << 32;
        }
        for (size_t b = 0; b < sizeof(double); ++b) std::memcpy(plane[b] + i, &r[b], sizeof r[b]);
    }
    for (; i < count; ++i) {
        unsigned char bytes[sizeof(double)];
        std::memcpy(bytes, in + i, sizeof bytes);
        for (size_t b = 0; b < sizeof(double); ++b) plane[b][i] = bytes[b];
    }
}

// The arrays' doubles as one sequence, zstd-compressed with a content checksum (so that a block damaged at rest,
// a result file or a checkpoint, is refused rather than merged). Layout 1 compresses all values byte-shuffled.
// Layout 2 (issue 17) compresses a mask of one bit per value, set where the value's bits are not all zero (-0.0
// is not zero), then only those values, byte-shuffled. A Markov-chain task's film at 1024² is about half zero
// bits (the pixels of a tile that no deposit reached), which zstd had to run through byte by byte: on
// cornell-box's mlt tasks that was most of a worker's encoding time.
enum class BodyLayout { AllValues = 1, NonZeroValues = 2 };

size_t maskBytes(size_t values) { return (values + 7) / 8; }
// Kept values unshuffled at a time when decoding layout 2 (32 KB).
constexpr size_t kWindow = 4096;

// Appends the arrays' values in layout 2 to `out`. The buffers are left uninitialized: they are written whole
// before they are read (zeroing them was a tenth of the encoding's time).
void appendCompressed(std::string &out, std::span<const std::span<const double>> arrays, int zstdLevel) {
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    const size_t maskSize = maskBytes(values);
    std::unique_ptr<double[]> kept(new double[values]);
    const std::unique_ptr<unsigned char[]> maskBuffer(new unsigned char[maskSize]);
    unsigned char *mask = maskBuffer.get();
    size_t n = 0, i = 0;
    unsigned bits = 0;
    for (const auto &a : arrays)
        for (const double v : a) {
            // Without a branch: whether a value is zero is a coin toss in a sparse film.
            const unsigned nonZero = std::bit_cast<uint64_t>(v) != 0;
            kept[n] = v;
            n += nonZero;
            bits |= nonZero << (i % 8);
            if (++i % 8 == 0) *mask++ = static_cast<unsigned char>(bits), bits = 0;
        }
    if (i % 8 != 0) *mask = static_cast<unsigned char>(bits);
    // The body is sized once the kept values are counted, and the kept values are freed before the compressed
    // copy exists: at most two copies of the values are alive, as in layout 1, whatever the share of zeros.
    const size_t bytes = maskSize + n * sizeof(double), bound = ZSTD_compressBound(bytes);
    const std::unique_ptr<unsigned char[]> body(new unsigned char[bytes]);
    std::memcpy(body.get(), maskBuffer.get(), maskSize);
    shuffle(kept.get(), n, n, 0, body.get() + maskSize);
    kept.reset();

    const std::unique_ptr<char[]> compressed(new char[bound]);
    const std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx *)> cctx(ZSTD_createCCtx(), ZSTD_freeCCtx);
    if (!cctx) throw std::bad_alloc();
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, zstdLevel);
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 1);
    const size_t size = ZSTD_compress2(cctx.get(), compressed.get(), bound, body.get(), bytes);
    if (ZSTD_isError(size)) throw FarmError(std::string("block compression failed: ") + ZSTD_getErrorName(size));
    out.append(compressed.get(), size);
}

[[noreturn]] void corrupt(const char *why) {
    throw FarmError(std::string("film block: corrupt or truncated data") + (why ? std::string(" (") + why + ")" : ""));
}

bool allFinite(std::span<const double> a) {
    bool finite = true;
    for (const double v : a) finite &= std::isfinite(v);
    return finite;
}

// Decompresses `compressed` (through `scratch`, grown as needed) into the arrays, which must take exactly its
// values; throws FarmError if they do not, if the data is corrupt or if a value is not finite.
void readCompressed(std::string_view compressed, std::span<const std::span<double>> arrays,
                    std::vector<unsigned char> &scratch, BodyLayout layout) {
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    const size_t maskSize = layout == BodyLayout::NonZeroValues ? maskBytes(values) : 0;
    const unsigned long long content = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
    // Layout 2 holds the mask and whole values, at most all of them; layout 1 exactly all of them.
    if (content == ZSTD_CONTENTSIZE_UNKNOWN || content == ZSTD_CONTENTSIZE_ERROR || content < maskSize ||
        (content - maskSize) % sizeof(double) != 0 || content > maskSize + values * sizeof(double) ||
        (layout == BodyLayout::AllValues && content != values * sizeof(double)))
        corrupt(nullptr);
    const size_t kept = (content - maskSize) / sizeof(double);
    // The body, then (layout 2) a window of kept values unshuffled (8-aligned, with a spare slot that the
    // branchless scatter may read): small enough to stay in the first-level cache between unshuffling and
    // scattering, where a whole second copy of the values cost a tenth more decoding time than layout 1.
    const size_t windowAt = (content + 7) / 8 * 8,
                 need = layout == BodyLayout::NonZeroValues ? windowAt + (kWindow + 1) * sizeof(double) : content;
    if (scratch.size() < need) scratch.resize(need);
    const size_t n = ZSTD_decompress(scratch.data(), content, compressed.data(), compressed.size());
    if (ZSTD_isError(n) || n != content) corrupt(ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short");
    const unsigned char *body = scratch.data() + maskSize;

    if (layout == BodyLayout::AllValues) {
        size_t first = 0;
        for (const auto &a : arrays) {
            unshuffle(body, values, first, a.size(), a.data());
            first += a.size();
            if (!allFinite(a)) throw FarmError("film block: non-finite value");
        }
        return;
    }
    const unsigned char *mask = scratch.data();
    size_t set = 0;
    for (size_t b = 0; b < maskSize; ++b) set += static_cast<size_t>(std::popcount(mask[b]));
    if (values % 8 != 0 && (mask[maskSize - 1] >> (values % 8)) != 0) corrupt("mask bits beyond the last value");
    if (set != kept) corrupt("mask and values disagree");
    auto *window = reinterpret_cast<double *>(scratch.data() + windowAt);
    size_t windowFirst = 0, windowEnd = 0;  // the kept values in the window
    window[0] = 0.0;
    // Value i of the sequence is bit i % 8 of mask byte i / 8, and the k-th set bit takes kept value k. Whole
    // bytes of set or clear bits (the runs of a dense film, the empty pixels of a sparse one) go eight values at
    // a time.
    size_t i = 0, k = 0;
    for (const auto &a : arrays) {
        double *out = a.data();
        for (const size_t end = i + a.size(); i < end;) {
            if (k + 8 > windowEnd && windowEnd < kept) {
                windowFirst = k, windowEnd = std::min(kept, k + kWindow);
                unshuffle(body, kept, windowFirst, windowEnd - windowFirst, window);
                window[windowEnd - windowFirst] = 0.0;
                if (!allFinite({window, windowEnd - windowFirst})) throw FarmError("film block: non-finite value");
            }
            const double *from = window + (k - windowFirst);
            const unsigned m = mask[i / 8];
            if (i % 8 == 0 && end - i >= 8 && (m == 0 || m == 0xff)) {
                if (m == 0) {
                    std::fill_n(out, 8, 0.0);
                } else {
                    std::memcpy(out, from, 8 * sizeof(double));
                    k += 8;
                }
                i += 8, out += 8;
                continue;
            }
            const unsigned nonZero = (m >> (i % 8)) & 1u;
            *out++ = nonZero ? *from : 0.0;
            k += nonZero;
            ++i;
        }
    }
}

std::string encodeTiles(const ImageBlock &block, const SplatTiles &tiles, int zstdLevel) {
    std::vector<uint32_t> present;
    std::vector<std::span<const double>> arrays;
    for (size_t t = 0; t < tiles.tileCount(); ++t)
        if (!tiles.tile(t).empty()) {
            present.push_back(static_cast<uint32_t>(t));
            arrays.push_back(tiles.tile(t));
        }
    const TileHeader h{{kTileMagic[0], kTileMagic[1], kTileMagic[2], kTileMagic[3]},
                       block.offsetX(),
                       block.offsetY(),
                       block.width(),
                       block.height(),
                       block.border(),
                       SplatTiles::kSize,
                       static_cast<uint32_t>(present.size()),
                       block.invalidSamples()};
    std::string out(sizeof h + present.size() * sizeof(uint32_t), '\0');
    std::memcpy(out.data(), &h, sizeof h);
    std::memcpy(out.data() + sizeof h, present.data(), present.size() * sizeof(uint32_t));
    appendCompressed(out, arrays, zstdLevel);
    return out;
}

void decodeDense(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch, BodyLayout layout) {
    Header h;
    if (data.size() < sizeof h) throw FarmError("film block: truncated header");
    std::memcpy(&h, data.data(), sizeof h);
    checkLayout(h, block);
    const std::span<double> arrays[] = {block.sumData(), block.weightData(), block.splatData()};
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    if (h.values != values) throw FarmError("film block: wrong number of values");
    readCompressed(data.substr(sizeof h), arrays, scratch, layout);
    block.setInvalidSamples(h.invalidSamples);
}

void decodeTiles(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch, BodyLayout layout) {
    TileHeader h;
    if (data.size() < sizeof h) throw FarmError("film block: truncated header");
    std::memcpy(&h, data.data(), sizeof h);
    checkLayout(h, block);
    if (h.tileSize != SplatTiles::kSize)
        throw FarmError("film block: tiles of " + std::to_string(h.tileSize) + " pixels, expected " +
                        std::to_string(SplatTiles::kSize));
    SplatTiles &tiles = *block.tiles();
    if (h.tiles > tiles.tileCount())
        throw FarmError("film block: " + std::to_string(h.tiles) + " tiles listed, the film has " +
                        std::to_string(tiles.tileCount()));
    if (data.size() - sizeof h < h.tiles * sizeof(uint32_t)) throw FarmError("film block: truncated tile list");
    std::vector<uint32_t> present(h.tiles);
    std::memcpy(present.data(), data.data() + sizeof h, present.size() * sizeof(uint32_t));
    for (size_t i = 0; i < present.size(); ++i) {
        const uint32_t t = present[i];
        if (t >= tiles.tileCount())
            throw FarmError("film block: tile " + std::to_string(t) + " out of range (the film has " +
                            std::to_string(tiles.tileCount()) + " tiles)");
        if (i > 0 && t <= present[i - 1])
            throw FarmError(t == present[i - 1] ? "film block: tile " + std::to_string(t) + " listed twice"
                                                : "film block: tiles out of order (" + std::to_string(t) + " after " +
                                                      std::to_string(present[i - 1]) + ")");
    }
    // The tiles are allocated only once the list is known to be sound, and exactly those listed are.
    tiles.clear();
    std::vector<std::span<double>> arrays;
    for (const uint32_t t : present) arrays.push_back(tiles.allocate(t));
    readCompressed(data.substr(sizeof h + present.size() * sizeof(uint32_t)), arrays, scratch, layout);
    block.setInvalidSamples(h.invalidSamples);
}

}  // namespace

std::string encodeBlock(const ImageBlock &block, int zstdLevel) {
    if (const SplatTiles *tiles = block.tiles()) return encodeTiles(block, *tiles, zstdLevel);
    const std::span<const double> arrays[] = {block.sumData(), block.weightData(), block.splatData()};
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    const Header h{{kMagic[0], kMagic[1], kMagic[2], kMagic[3]},
                   block.offsetX(),
                   block.offsetY(),
                   block.width(),
                   block.height(),
                   block.border(),
                   block.invalidSamples(),
                   values};
    std::string out(sizeof h, '\0');
    std::memcpy(out.data(), &h, sizeof h);
    appendCompressed(out, arrays, zstdLevel);
    return out;
}

void decodeBlock(std::string_view data, ImageBlock &block) {
    std::vector<unsigned char> scratch;
    decodeBlock(data, block, scratch);
}

void decodeBlock(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch) {
    if (data.size() < sizeof kMagic) throw FarmError("film block: truncated header");
    // The magic without its layout character, then the layout.
    const bool tiles = std::memcmp(data.data(), kTileMagic, sizeof kTileMagic - 1) == 0;
    if ((!tiles && std::memcmp(data.data(), kMagic, sizeof kMagic - 1) != 0) || (data[3] != '1' && data[3] != '2'))
        throw FarmError("film block: not a pathfarm block");
    const BodyLayout layout = data[3] == '1' ? BodyLayout::AllValues : BodyLayout::NonZeroValues;
    if (tiles != (block.tiles() != nullptr))
        throw FarmError(tiles ? "film block: tiles where a dense block was expected"
                              : "film block: a dense block where tiles were expected");
    tiles ? decodeTiles(data, block, scratch, layout) : decodeDense(data, block, scratch, layout);
}

}  // namespace pf::farm
