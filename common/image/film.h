// Film: resolution, crop window and reconstruction filter (Mitsuba's hdrfilm/ldrfilm), plus the
// ImageBlock that accumulates filtered samples. Rendering writes into per-tile ImageBlocks that are
// merged in a fixed order, so images are bit-identical whatever the thread count.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/spectrum.h"
#include "core/vector.h"
#include "image/bitmap.h"
#include "image/rfilter.h"
#include "image/splat_tiles.h"
#include "image/tonemap.h"
#include "scene/object.h"

namespace pf {

// How an ImageBlock holds its pixels: Dense, arrays of all 7 doubles per pixel; Tiles, splat sums only, in
// tiles allocated where deposits land (image/splat_tiles.h), for the film of a chain task (render/chain.h).
// A storage mode rather than a type of its own, so that the chains keep depositing through ImageBlock& and
// the codec, the merge and the master handle one kind of block.
enum class BlockStorage { Dense, Tiles };

class ImageBlock {
public:
    // A block covering raster pixels [offsetX, offsetX+w) x [offsetY, offsetY+h) of a film of size
    // (filmW, filmH), with a border of the filter's radius so that samples near the edge are kept.
    ImageBlock(int offsetX, int offsetY, int w, int h, const ReconstructionFilter *filter,
               BlockStorage storage = BlockStorage::Dense);
    // Filtered sample: adds filter(x) * value and filter(x) weight to nearby pixels. A Tiles block holds
    // splats only: put() on it throws std::logic_error.
    void put(const Vec2 &raster, const Spectrum &value);
    // Splat (light tracing, MLT): adds filter(x) * value to nearby pixels, kept apart from put()'s sums
    // so that it is not divided by the filter weights (see Film::develop).
    void splat(const Vec2 &raster, const Spectrum &value);
    // Asks the cache for the splat sums that splat(raster, ...) will add to (a Dense block with a filter; else
    // nothing). Light tracing's splats land anywhere on a large film: added one after another, each waited
    // for its pixels' memory (72% of deposit()'s time in a 1024² BDPT profile); callers issue this a few splats
    // ahead so that the loads overlap.
    void prefetchSplat(const Vec2 &raster) const;
    // Adds another block (which must lie inside this one's region incl. border) into this one, which must
    // be Dense; a Tiles block adds its allocated tiles only (the rest is zeros, and x + 0 = x: the same
    // bits as adding it dense, since sums that start at +0 never hold -0).
    void merge(const ImageBlock &other);
    void clear();
    // Samples put() or splat() dropped because their value or position was NaN or infinite (Mitsuba
    // warns about these too); merge() adds the counts, so a render can report them.
    uint64_t invalidSamples() const { return invalid_; }

    int offsetX() const { return ox_; }
    int offsetY() const { return oy_; }
    int width() const { return w_; }
    int height() const { return h_; }
    int border() const { return border_; }
    // Accessors over the block's storage including the border; (x, y) in raster coordinates.
    Spectrum weightedSum(int x, int y) const;
    double weight(int x, int y) const;
    Spectrum splatSum(int x, int y) const;
    // The raw storage including the border, row-major: 3 weighted sums, 1 weight and 3 splat sums per
    // pixel. The farm ships blocks between processes through these, bit for bit. Empty for a Tiles block,
    // whose storage is tiles().
    std::span<const double> sumData() const { return sum_; }
    std::span<const double> weightData() const { return weight_; }
    std::span<const double> splatData() const { return splat_; }
    std::span<double> sumData() { return sum_; }
    std::span<double> weightData() { return weight_; }
    std::span<double> splatData() { return splat_; }
    void setInvalidSamples(uint64_t n) { invalid_ = n; }
    // A Tiles block's splat sums over the storage grid (the border included); null for a Dense block.
    const SplatTiles *tiles() const { return tiles_ ? &*tiles_ : nullptr; }
    SplatTiles *tiles() { return tiles_ ? &*tiles_ : nullptr; }
    // Doubles the block holds (what it costs in memory, 8 bytes each).
    size_t storedValues() const;

private:
    size_t index(int x, int y) const;
    // The storage pixels [x0, x1] x [y0, y1] within the filter's radius of `raster` (finite), relative to pixel
    // centres at (px, py); empty when none lies in the storage.
    struct Footprint {
        int x0, x1, y0, y1;
        double px, py;
        bool empty() const { return x0 > x1 || y0 > y1; }
    };
    Footprint footprint(const Vec2 &raster) const;
    // Adds filter(x) * value to `channels` (and filter(x) to the weights if `weighted`) around `raster`.
    void deposit(const Vec2 &raster, const Spectrum &value, std::vector<double> &channels, bool weighted);
    // Adds the splat sums of a Tiles block whose storage starts at raster pixel (loX, loY).
    void mergeTiles(const SplatTiles &tiles, int loX, int loY);
    int ox_, oy_, w_, h_, border_;
    const ReconstructionFilter *filter_;
    std::vector<double> sum_;     // 3 per pixel
    std::vector<double> weight_;  // 1 per pixel
    std::vector<double> splat_;   // 3 per pixel

    std::optional<SplatTiles> tiles_;  // instead of the three arrays in a Tiles block
    uint64_t invalid_ = 0;
};

class Film : public Object {
public:
    int width() const { return width_; }  // full film size
    int height() const { return height_; }
    // The crop window (Mitsuba's cropOffsetX/Y, cropWidth/Height); rendering covers only this region.
    int cropX() const { return cropX_; }
    int cropY() const { return cropY_; }
    int cropWidth() const { return cropW_; }
    int cropHeight() const { return cropH_; }
    const ReconstructionFilter &filter() const { return *filter_; }
    bool isHDR() const { return hdr_; }  // hdrfilm vs ldrfilm
    double exposure() const { return exposure_; }
    // ldrfilm's transfer curve: -1 = sRGB (Mitsuba's default), otherwise a pure power 1/gamma.
    double gamma() const { return gamma_; }
    // ldrfilm's tone mapping of the PNG (hdrfilm: the default, sRGB without exposure).
    const ToneMap &toneMap() const { return toneMap_; }
    // The EXR's pixelFormat and componentFormat (hdrfilm; float32 unless componentFormat is given), and
    // the PNG's pixelFormat (ldrfilm).
    const EXRFormat &exrFormat() const { return exrFormat_; }
    PixelFormat pngPixelFormat() const { return pngPixels_; }
    // Output format the scene asked for: "openexr", "rgbe" or "pfm" (hdrfilm), "png" or "jpeg" (ldrfilm).
    const std::string &fileFormat() const { return fileFormat_; }
    // Mitsuba's highQualityEdges: also sample raster positions up to the filter border outside the crop
    // window, so that edge pixels receive their full filter footprint.
    bool highQualityEdges() const { return highQualityEdges_; }

    // Limits on the film size: absurd resolutions are rejected before anything is allocated.
    static constexpr int kMaxSide = 32768;
    static constexpr int64_t kMaxPixels = int64_t(1) << 28;

    // Changes the resolution and resets the crop window to the whole film (benchmarks, previews).
    void resize(int width, int height) {
        width_ = cropW_ = width;
        height_ = cropH_ = height;
        cropX_ = cropY_ = 0;
    }

    // Develops a block that covers the crop window into an image: weighted sum / weight plus
    // splatScale * splat sum / the filter's coverage of the pixel (filterCoverage along x times along y).
    Bitmap develop(const ImageBlock &block, double splatScale) const;

    // An hdrfilm without crop; a null filter means Mitsuba's default (gaussian, stddev 0.5). Throws
    // SceneError for a size outside [1, kMaxSide] per side or above kMaxPixels in total.
    static std::shared_ptr<Film> create(int width, int height, std::shared_ptr<ReconstructionFilter> filter);

protected:
    int width_ = 768, height_ = 576;
    int cropX_ = 0, cropY_ = 0, cropW_ = 768, cropH_ = 576;
    std::shared_ptr<ReconstructionFilter> filter_;
    bool hdr_ = true;
    double exposure_ = 0.0;
    double gamma_ = -1.0;
    ToneMap toneMap_;
    EXRFormat exrFormat_;
    PixelFormat pngPixels_ = PixelFormat::RGB;
    std::string fileFormat_ = "openexr";
    bool highQualityEdges_ = false;
};

// Per pixel i of a row of n pixels, the integral of the 1D filter centred on the pixel over the row,
// int_0^n f(i + 1/2 - t) dt: 1 for a box filter, the filter's full integral away from the ends.
std::vector<double> filterCoverage(const ReconstructionFilter &filter, int n);

}  // namespace pf
