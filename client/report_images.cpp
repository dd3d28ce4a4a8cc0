#include "report_images.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace pf::client {

double autoExposure(const Bitmap &image) {
    // The log-average (Reinhard, eq. 1) over the pixels that receive light: black background pixels,
    // many in caustic scenes, would otherwise pull it down and overexpose everything else. The small
    // delta keeps near-black pixels from sending the mean to -infinity.
    constexpr double kDelta = 1e-4;
    double sumLog = 0;
    size_t lit = 0;
    for (size_t p = 0; p < image.rgb.size() / 3; ++p) {
        const double y = 0.2126 * image.rgb[3 * p] + 0.7152 * image.rgb[3 * p + 1] + 0.0722 * image.rgb[3 * p + 2];
        if (!(y > 0)) continue;
        sumLog += std::log(kDelta + y);
        ++lit;
    }
    if (lit == 0) return 0;
    return std::log2(0.18 / std::exp(sumLog / static_cast<double>(lit)));
}

std::vector<Region> regionsOfLargestError(const std::vector<ErrorMap> &maps, int count) {
    if (maps.empty() || count <= 0) return {};
    const int w = maps[0].width, h = maps[0].height;
    const int size = std::clamp(std::min(w, h) / 5, 1, 64);
    std::vector<std::pair<double, Region>> tiles;
    for (int ty = 0; ty + size <= h; ty += size)
        for (int tx = 0; tx + size <= w; tx += size) {
            double sum = 0;
            for (const ErrorMap &m : maps) {
                if (m.width != w || m.height != h) throw std::invalid_argument("error maps of different sizes");
                for (int y = ty; y < ty + size; ++y)
                    for (int x = tx; x < tx + size; ++x) sum += m.values[static_cast<size_t>(y) * w + x];
            }
            tiles.push_back({sum, Region{tx, ty, size}});
        }
    const size_t k = std::min(tiles.size(), static_cast<size_t>(count));
    std::partial_sort(tiles.begin(), tiles.begin() + static_cast<std::ptrdiff_t>(k), tiles.end(),
                      [](const auto &a, const auto &b) { return a.first > b.first; });
    std::vector<Region> out;
    for (size_t i = 0; i < k; ++i) out.push_back(tiles[i].second);
    return out;
}

Bitmap crop(const Bitmap &image, const Region &r) {
    if (r.x < 0 || r.y < 0 || r.size < 1 || r.x + r.size > image.width || r.y + r.size > image.height)
        throw std::invalid_argument("crop region outside the image");
    Bitmap out(r.size, r.size);
    for (int y = 0; y < r.size; ++y)
        std::copy_n(image.rgb.begin() + (static_cast<std::ptrdiff_t>(r.y + y) * image.width + r.x) * 3, r.size * 3,
                    out.rgb.begin() + static_cast<std::ptrdiff_t>(y) * r.size * 3);
    return out;
}

}  // namespace pf::client
