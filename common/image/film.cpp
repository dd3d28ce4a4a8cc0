// ImageBlock accumulation and film development (Mitsuba's ImageBlock::put and Film::develop; pbrt-v3
// §7.9 "Film and the imaging pipeline" for the weighted-average reconstruction).
//
// Reconstruction is the weighted average I(p) = sum_i f(x_i - p) L_i / sum_i f(x_i - p) over the samples
// x_i near pixel centre p = (i + 0.5, j + 0.5) (pbrt-v3 eq. 7.12). With samples spread uniformly over the
// crop window this converges to the image filtered with f normalized over the window:
// I(p) = int f(x - p) L(x) dx / int f(x - p) dx. Splats from light tracing and Metropolis methods are
// estimates of a density of L over the image plane, not samples of L at chosen points, so they cannot be
// divided by their own weights; they are spread with the same filter and divided by its exact integral
// over the window instead (filterCoverage), which gives the same filtered image. Every integrator then
// converges to the same pixels, also at edges and at the window's border (Mitsuba does the former but
// not the latter for its light image).
#include "image/film.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pf {

namespace {

// Taps per axis of the widest accepted filter: pixels with |i + 0.5 - x| <= radius.
constexpr int kMaxTaps = 2 * static_cast<int>(kMaxFilterRadius) + 2;

// floor and ceil of a value within int range, exactly, from the truncating conversion: without SSE4.1's
// roundsd, std::floor and std::ceil are a dozen instructions each, four of them per sample (issue 17).
int floorInRange(double v) {
    const int i = static_cast<int>(v);
    return i - (v < i);
}
int ceilInRange(double v) {
    const int i = static_cast<int>(v);
    return i + (v > i);
}

}  // namespace

ImageBlock::ImageBlock(int offsetX, int offsetY, int w, int h, const ReconstructionFilter *filter, BlockStorage storage)
    : ox_(offsetX), oy_(offsetY), w_(w), h_(h), border_(filter ? filter->borderSize() : 0), filter_(filter) {
    if (w < 0 || h < 0) throw std::invalid_argument("ImageBlock: negative size");
    if (filter && !(filter->radius() > 0 && filter->radius() <= kMaxFilterRadius))
        throw std::invalid_argument("ImageBlock: filter radius outside (0, kMaxFilterRadius]");
    if (storage == BlockStorage::Tiles) {
        tiles_.emplace(w + 2 * border_, h + 2 * border_);
        return;
    }
    const size_t pixels = static_cast<size_t>(w + 2 * border_) * static_cast<size_t>(h + 2 * border_);
    sum_.assign(3 * pixels, 0.0);
    weight_.assign(pixels, 0.0);
    splat_.assign(3 * pixels, 0.0);
}

size_t ImageBlock::index(int x, int y) const {
    const int sx = x - (ox_ - border_), sy = y - (oy_ - border_);
    if (sx < 0 || sy < 0 || sx >= w_ + 2 * border_ || sy >= h_ + 2 * border_)
        throw std::out_of_range("ImageBlock: pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                ") outside the block");
    return static_cast<size_t>(sy) * static_cast<size_t>(w_ + 2 * border_) + static_cast<size_t>(sx);
}

void ImageBlock::put(const Vec2 &raster, const Spectrum &value) {
    if (tiles_) throw std::logic_error("ImageBlock::put: a Tiles block holds splats only");
    deposit(raster, value, sum_, true);
}

void ImageBlock::splat(const Vec2 &raster, const Spectrum &value) { deposit(raster, value, splat_, false); }

ImageBlock::Footprint ImageBlock::footprint(const Vec2 &raster) const {
    // The storage spans pixels [lo, hi] per axis, the border included. Work relative to pixel centres.
    const int loX = ox_ - border_, hiX = ox_ + w_ + border_ - 1;
    const int loY = oy_ - border_, hiY = oy_ + h_ + border_ - 1;
    const double r = filter_->radius();
    const double px = raster.x - 0.5, py = raster.y - 0.5;
    // Reject far-away samples in floating point first, so that the int conversions below cannot overflow.
    if (px + r < loX || px - r > hiX || py + r < loY || py - r > hiY) return {0, -1, 0, -1, px, py};
    return {std::max(loX, ceilInRange(px - r)),
            std::min(hiX, floorInRange(px + r)),
            std::max(loY, ceilInRange(py - r)),
            std::min(hiY, floorInRange(py + r)),
            px,
            py};
}

void ImageBlock::prefetchSplat(const Vec2 &raster) const {
    if (tiles_ || !filter_ || !std::isfinite(raster.x) || !std::isfinite(raster.y)) return;
    const Footprint fp = footprint(raster);
    if (fp.empty()) return;
    // A footprint row's splat sums are 3 doubles per pixel; one address per 64 bytes and the last one reach every
    // cache line they touch.
    const size_t stride = static_cast<size_t>(w_ + 2 * border_), n = 3 * static_cast<size_t>(fp.x1 - fp.x0 + 1);
    for (int y = fp.y0; y <= fp.y1; ++y) {
        const double *row = splat_.data() + 3 * (static_cast<size_t>(y - (oy_ - border_)) * stride +
                                                 static_cast<size_t>(fp.x0 - (ox_ - border_)));
        for (size_t k = 0; k < n; k += 8) __builtin_prefetch(row + k, 1);
        __builtin_prefetch(row + n - 1, 1);
    }
}

void ImageBlock::deposit(const Vec2 &raster, const Spectrum &value, std::vector<double> &channels, bool weighted) {
    if (!value.isFinite() || !std::isfinite(raster.x) || !std::isfinite(raster.y)) {
        ++invalid_;
        return;
    }
    // The storage spans pixels [lo, hi] per axis, the border included.
    const int loX = ox_ - border_, hiX = ox_ + w_ + border_ - 1;
    const int loY = oy_ - border_, hiY = oy_ + h_ + border_ - 1;
    const auto add = [&](size_t i, double w) {
        channels[3 * i] += w * value.r;
        channels[3 * i + 1] += w * value.g;
        channels[3 * i + 2] += w * value.b;
        if (weighted) weight_[i] += w;
    };
    if (!filter_) {
        // Without a filter a sample counts, with weight one, for the pixel that contains it.
        const double x = std::floor(raster.x), y = std::floor(raster.y);
        if (x < loX || y < loY || x > hiX || y > hiY) return;
        if (tiles_) {
            const double one = 1.0;
            tiles_->addRow(static_cast<int>(x) - loX, static_cast<int>(y) - loY, 1, &one, 1.0, value);
            return;
        }
        add(index(static_cast<int>(x), static_cast<int>(y)), 1.0);
        return;
    }
    const Footprint fp = footprint(raster);
    if (fp.empty()) return;
    const auto [x0, x1, y0, y1, px, py] = fp;
    double wx[kMaxTaps], wy[kMaxTaps];
    for (int x = x0; x <= x1; ++x) wx[x - x0] = filter_->eval(x - px);
    for (int y = y0; y <= y1; ++y) wy[y - y0] = filter_->eval(y - py);
    if (tiles_) {
        for (int y = y0; y <= y1; ++y) tiles_->addRow(x0 - loX, y - loY, x1 - x0 + 1, wx, wy[y - y0], value);
        return;
    }
    // The footprint lies inside the storage (clamped above): rows are addressed without index()'s checks.
    const size_t stride = static_cast<size_t>(w_ + 2 * border_);
    for (int y = y0; y <= y1; ++y) {
        size_t i = static_cast<size_t>(y - loY) * stride + static_cast<size_t>(x0 - loX);
        for (int x = x0; x <= x1; ++x, ++i) add(i, wx[x - x0] * wy[y - y0]);
    }
}

// Element-wise addition, row by row over contiguous storage: for the same blocks merged in the same
// order the result is the same bits, which is what makes renders independent of the thread count.
void ImageBlock::merge(const ImageBlock &other) {
    const int oLoX = other.ox_ - other.border_, oLoY = other.oy_ - other.border_;
    const int oW = other.w_ + 2 * other.border_, oH = other.h_ + 2 * other.border_;
    if (oLoX < ox_ - border_ || oLoY < oy_ - border_ || oLoX + oW > ox_ + w_ + border_ ||
        oLoY + oH > oy_ + h_ + border_)
        throw std::invalid_argument("ImageBlock::merge: the other block (with its border) does not fit");
    if (tiles_) throw std::logic_error("ImageBlock::merge: into a Tiles block");
    invalid_ += other.invalid_;
    if (other.tiles_) return mergeTiles(*other.tiles_, oLoX, oLoY);
    if (oW == 0 || oH == 0) return;
    for (int row = 0; row < oH; ++row) {
        const size_t src = static_cast<size_t>(row) * static_cast<size_t>(oW);
        const size_t dst = index(oLoX, oLoY + row);
        for (size_t k = 0; k < static_cast<size_t>(oW); ++k) weight_[dst + k] += other.weight_[src + k];
        for (size_t k = 0; k < 3 * static_cast<size_t>(oW); ++k) {
            sum_[3 * dst + k] += other.sum_[3 * src + k];
            splat_[3 * dst + k] += other.splat_[3 * src + k];
        }
    }
}

void ImageBlock::mergeTiles(const SplatTiles &tiles, int loX, int loY) {
    for (size_t t = 0; t < tiles.tileCount(); ++t) {
        const std::span<const double> values = tiles.tile(t);
        if (values.empty()) continue;
        const SplatTiles::Rect r = tiles.rect(t);
        const size_t rowValues = 3 * static_cast<size_t>(r.width);
        for (int row = 0; row < r.height; ++row) {
            double *dst = splat_.data() + 3 * index(loX + r.x, loY + r.y + row);
            const double *src = values.data() + static_cast<size_t>(row) * rowValues;
            for (size_t k = 0; k < rowValues; ++k) dst[k] += src[k];
        }
    }
}

void ImageBlock::clear() {
    if (tiles_) tiles_->clear();
    std::fill(sum_.begin(), sum_.end(), 0.0);
    std::fill(weight_.begin(), weight_.end(), 0.0);
    std::fill(splat_.begin(), splat_.end(), 0.0);
    invalid_ = 0;
}

// A Tiles block has no weighted sums and weights: nothing is put() into it.
Spectrum ImageBlock::weightedSum(int x, int y) const {
    const size_t i = index(x, y);
    if (tiles_) return Spectrum(0.0);
    return {sum_[3 * i], sum_[3 * i + 1], sum_[3 * i + 2]};
}

double ImageBlock::weight(int x, int y) const {
    const size_t i = index(x, y);
    return tiles_ ? 0.0 : weight_[i];
}

Spectrum ImageBlock::splatSum(int x, int y) const {
    const size_t i = index(x, y);
    if (tiles_) return tiles_->at(x - (ox_ - border_), y - (oy_ - border_));
    return {splat_[3 * i], splat_[3 * i + 1], splat_[3 * i + 2]};
}

size_t ImageBlock::storedValues() const {
    return sum_.size() + weight_.size() + splat_.size() + (tiles_ ? tiles_->storedValues() : 0);
}

Bitmap Film::develop(const ImageBlock &block, double splatScale) const {
    if (block.offsetX() > 0 || block.offsetY() > 0 || block.offsetX() + block.width() < cropW_ ||
        block.offsetY() + block.height() < cropH_)
        throw std::invalid_argument("Film::develop: the block does not cover the crop window");
    const std::vector<double> nx = filterCoverage(*filter_, cropW_), ny = filterCoverage(*filter_, cropH_);
    Bitmap img(cropW_, cropH_);
    for (int y = 0; y < cropH_; ++y)
        for (int x = 0; x < cropW_; ++x) {
            // A pixel no sample reached (weight zero) has no estimate from put(); it shows only splats.
            const double w = block.weight(x, y);
            const Spectrum filtered = w != 0 ? block.weightedSum(x, y) / w : Spectrum(0.0);
            img.set(x, y, filtered + block.splatSum(x, y) * (splatScale / (nx[x] * ny[y])));
        }
    return img;
}

std::vector<double> filterCoverage(const ReconstructionFilter &filter, int n) {
    // Composite Simpson over pieces of half a pixel: the filters are smooth inside a piece, and their kinks
    // and jumps (tent at 0, box at +-1/2, the cubics at +-1) fall on piece boundaries.
    constexpr int kSteps = 64;
    const double r = filter.radius();
    const auto integrate = [&](double a, double b) {
        const double h = (b - a) / kSteps;
        double sum = filter.eval(a) + filter.eval(b);
        for (int k = 1; k < kSteps; ++k) sum += filter.eval(a + k * h) * (k % 2 ? 4.0 : 2.0);
        return sum * h / 3.0;
    };
    // Coverage of pixel i: the integral of f(i + 1/2 - t) for t in [0, n), taken in u = i + 1/2 - t over
    // [max(-r, i + 1/2 - n), min(r, i + 1/2)].
    std::vector<double> coverage(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
        const double lo = std::max(-r, i + 0.5 - n), hi = std::min(r, i + 0.5);
        double sum = 0;
        for (double a = lo; a < hi;) {
            const double b = std::min(hi, (std::floor(2.0 * a) + 1.0) / 2.0);
            sum += integrate(a, b);
            a = b;
        }
        coverage[static_cast<size_t>(i)] = sum;
    }
    return coverage;
}

std::shared_ptr<Film> Film::create(int width, int height, std::shared_ptr<ReconstructionFilter> filter) {
    if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide ||
        static_cast<int64_t>(width) * height > kMaxPixels)
        throw SceneError("film size " + std::to_string(width) + "x" + std::to_string(height) + " is outside 1.." +
                         std::to_string(kMaxSide) + " per side or above " + std::to_string(kMaxPixels) + " pixels");
    auto film = std::make_shared<Film>();
    film->width_ = film->cropW_ = width;
    film->height_ = film->cropH_ = height;
    film->filter_ = filter ? std::move(filter) : std::make_shared<GaussianFilter>();
    return film;
}

}  // namespace pf
