// Tile-sparse storage of splat sums, the pixels of a chain task's film (render/chain.h). A burst task
// (render/burst.h) launches its chains from one band of the crop window and deposits on a few percent of the
// pixels, so a dense film of the whole window would be mostly zeros that every task allocates, clears,
// encodes, ships, decodes and merges. Here the storage grid (an ImageBlock's pixels, its filter border included) is cut
// into square tiles of kSize pixels, and a tile is allocated, as zeros, by the first deposit that touches it.
// A pixel accumulates the same additions in the same order as in a dense array, so its bits are the same,
// and a tile never touched is exactly the zeros a dense film would hold there.
//
// Splats only: chain films receive nothing else (film.cpp: every Markov-chain deposit is a splat), so the
// weighted sums and weights of put() (4 of a dense block's 7 doubles per pixel) have no tiles at all.
#pragma once
#include <cstddef>
#include <span>
#include <vector>

#include "core/spectrum.h"

namespace pf {

class SplatTiles {
public:
    // Tiles of 8 x 8 pixels (1.5 KiB). Burst deposits are thin and scattered, not a compact band: mept's
    // tasks on volumetric-caustic-small at 1024² (passes of 2^18 mutations) left 2-3% of the pixels nonzero,
    // yet touched 60-67% of the 32 x 32 tiles, 40-48% of 16 x 16 ones and 22-28% of 8 x 8 ones. Smaller
    // tiles would cost more in the tile list and in the per-tile bookkeeping than they save.
    static constexpr int kSize = 8;

    // A storage grid of width x height pixels (both >= 0), no tile allocated.
    SplatTiles(int width, int height);

    // A tile's pixels within the grid: tiles in the last column and row are cut at the grid's edge.
    struct Rect {
        int x, y, width, height;
    };
    size_t tileCount() const { return tiles_.size(); }
    Rect rect(size_t tile) const;
    // Tile `tile`'s values: 3 per pixel, rows of rect(tile).width pixels; empty while not allocated.
    std::span<const double> tile(size_t tile) const { return tiles_[tile]; }
    // The same, allocated as zeros if it was not.
    std::span<double> allocate(size_t tile);
    // Values held by the allocated tiles.
    size_t storedValues() const { return stored_; }

    // Adds wx[k] * wy * value to pixel (x + k, y) for k < n, allocating tiles as it goes (the pixels must
    // lie in the grid).
    void addRow(int x, int y, int n, const double *wx, double wy, const Spectrum &value);
    // Pixel (x, y)'s sum (inside the grid): zero where no tile is allocated.
    Spectrum at(int x, int y) const;
    // Frees every tile.
    void clear();

private:
    size_t tileOf(int x, int y) const {
        return static_cast<size_t>(y / kSize) * static_cast<size_t>(tilesX_) + static_cast<size_t>(x / kSize);
    }
    // Index of pixel (x, y)'s first value within its tile.
    size_t offsetIn(size_t tile, int x, int y) const;

    int width_, height_, tilesX_;
    std::vector<std::vector<double>> tiles_;
    size_t stored_ = 0;
};

}  // namespace pf
