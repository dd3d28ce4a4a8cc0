#include "image/splat_tiles.h"

#include <algorithm>

namespace pf {

SplatTiles::SplatTiles(int width, int height) : width_(width), height_(height), tilesX_((width + kSize - 1) / kSize) {
    tiles_.resize(static_cast<size_t>(tilesX_) * static_cast<size_t>((height + kSize - 1) / kSize));
}

SplatTiles::Rect SplatTiles::rect(size_t tile) const {
    const int x = static_cast<int>(tile % static_cast<size_t>(tilesX_)) * kSize;
    const int y = static_cast<int>(tile / static_cast<size_t>(tilesX_)) * kSize;
    return {x, y, std::min(kSize, width_ - x), std::min(kSize, height_ - y)};
}

std::span<double> SplatTiles::allocate(size_t tile) {
    std::vector<double> &t = tiles_[tile];
    if (t.empty()) {
        const Rect r = rect(tile);
        t.assign(3 * static_cast<size_t>(r.width) * static_cast<size_t>(r.height), 0.0);
        stored_ += t.size();
    }
    return t;
}

size_t SplatTiles::offsetIn(size_t tile, int x, int y) const {
    const Rect r = rect(tile);
    return 3 * (static_cast<size_t>(y - r.y) * static_cast<size_t>(r.width) + static_cast<size_t>(x - r.x));
}

void SplatTiles::addRow(int x, int y, int n, const double *wx, double wy, const Spectrum &value) {
    for (int k = 0; k < n;) {
        // The run of the row's pixels that lies in one tile: up to that tile's right edge.
        const int end = std::min(n, k + kSize - (x + k) % kSize);
        const size_t t = tileOf(x + k, y);
        double *p = allocate(t).data() + offsetIn(t, x + k, y);
        for (; k < end; ++k, p += 3) {
            // The dense block's expression (film.cpp), so that the sums have its bits.
            const double w = wx[k] * wy;
            p[0] += w * value.r;
            p[1] += w * value.g;
            p[2] += w * value.b;
        }
    }
}

Spectrum SplatTiles::at(int x, int y) const {
    const size_t t = tileOf(x, y);
    if (tiles_[t].empty()) return Spectrum(0.0);
    const double *p = tiles_[t].data() + offsetIn(t, x, y);
    return {p[0], p[1], p[2]};
}

void SplatTiles::clear() {
    for (std::vector<double> &t : tiles_) std::vector<double>().swap(t);
    stored_ = 0;
}

}  // namespace pf
