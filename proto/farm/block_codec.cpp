#include "farm/block_codec.h"

#include <zstd.h>

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
    std::vector<unsigned char> shuffled(values * sizeof(double));
    const size_t n = ZSTD_decompress(shuffled.data(), shuffled.size(), compressed.data(), compressed.size());
    if (ZSTD_isError(n) || n != shuffled.size())
        throw FarmError(std::string("film block: ") + (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short data"));

    size_t i = 0;
    for (const auto &a : arrays)
        for (double &v : a) {
            unsigned char bytes[sizeof(double)];
            for (size_t b = 0; b < sizeof(double); ++b) bytes[b] = shuffled[b * values + i];
            std::memcpy(&v, bytes, sizeof v);
            if (!std::isfinite(v)) throw FarmError("film block: non-finite value");
            ++i;
        }
    block.setInvalidSamples(h.invalidSamples);
}

}  // namespace pf::farm
