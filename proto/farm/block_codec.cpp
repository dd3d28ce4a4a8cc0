#include "farm/block_codec.h"

#include <zstd.h>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

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

constexpr char kMagic[4] = {'P', 'F', 'B', '1'}, kTileMagic[4] = {'P', 'F', 'T', '1'};

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

// Appends the arrays' doubles to `out`, byte-shuffled (all arrays as one sequence) and compressed. The
// buffers are left uninitialized: both are written whole before they are read (zeroing them was a tenth of
// the encoding's time).
void appendCompressed(std::string &out, std::span<const std::span<const double>> arrays, int zstdLevel) {
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    const size_t bytes = values * sizeof(double);
    const std::unique_ptr<unsigned char[]> shuffled(new unsigned char[bytes]);
    size_t first = 0;
    for (const auto &a : arrays) {
        shuffle(a.data(), a.size(), values, first, shuffled.get());
        first += a.size();
    }

    const size_t bound = ZSTD_compressBound(bytes);
    const std::unique_ptr<char[]> compressed(new char[bound]);
    // With a content checksum, so that a block damaged at rest (a result file, a checkpoint) is refused
    // rather than merged.
    const std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx *)> cctx(ZSTD_createCCtx(), ZSTD_freeCCtx);
    if (!cctx) throw std::bad_alloc();
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_compressionLevel, zstdLevel);
    ZSTD_CCtx_setParameter(cctx.get(), ZSTD_c_checksumFlag, 1);
    const size_t n = ZSTD_compress2(cctx.get(), compressed.get(), bound, shuffled.get(), bytes);
    if (ZSTD_isError(n)) throw FarmError(std::string("block compression failed: ") + ZSTD_getErrorName(n));
    out.append(compressed.get(), n);
}

// Decompresses `compressed` (through `scratch`) into the arrays, which must take exactly its values; throws
// FarmError if they do not, if the data is corrupt or if a value is not finite.
void readCompressed(std::string_view compressed, std::span<const std::span<double>> arrays,
                    std::vector<unsigned char> &scratch) {
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    const unsigned long long content = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
    if (content != values * sizeof(double)) throw FarmError("film block: corrupt or truncated data");
    if (scratch.size() < values * sizeof(double)) scratch.resize(values * sizeof(double));
    const unsigned char *shuffled = scratch.data();
    const size_t n = ZSTD_decompress(scratch.data(), values * sizeof(double), compressed.data(), compressed.size());
    if (ZSTD_isError(n) || n != values * sizeof(double))
        throw FarmError(std::string("film block: corrupt or truncated data (") +
                        (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short") + ")");

    size_t first = 0;
    for (const auto &a : arrays) {
        unshuffle(shuffled, values, first, a.size(), a.data());
        first += a.size();
        bool finite = true;
        for (const double v : a) finite &= std::isfinite(v);
        if (!finite) throw FarmError("film block: non-finite value");
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

void decodeDense(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch) {
    Header h;
    if (data.size() < sizeof h) throw FarmError("film block: truncated header");
    std::memcpy(&h, data.data(), sizeof h);
    checkLayout(h, block);
    const std::span<double> arrays[] = {block.sumData(), block.weightData(), block.splatData()};
    size_t values = 0;
    for (const auto &a : arrays) values += a.size();
    if (h.values != values) throw FarmError("film block: wrong number of values");
    readCompressed(data.substr(sizeof h), arrays, scratch);
    block.setInvalidSamples(h.invalidSamples);
}

void decodeTiles(std::string_view data, ImageBlock &block, std::vector<unsigned char> &scratch) {
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
    readCompressed(data.substr(sizeof h + present.size() * sizeof(uint32_t)), arrays, scratch);
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
    const bool tiles = std::memcmp(data.data(), kTileMagic, sizeof kTileMagic) == 0;
    if (!tiles && std::memcmp(data.data(), kMagic, sizeof kMagic) != 0)
        throw FarmError("film block: not a pathfarm block");
    if (tiles != (block.tiles() != nullptr))
        throw FarmError(tiles ? "film block: tiles where a dense block was expected"
                              : "film block: a dense block where tiles were expected");
    tiles ? decodeTiles(data, block, scratch) : decodeDense(data, block, scratch);
}

}  // namespace pf::farm
