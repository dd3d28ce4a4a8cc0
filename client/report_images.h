// The pictures of the comparison report: one exposure for every tonemapped image, and the regions
// worth zooming into.
#pragma once
#include <vector>

#include "image/bitmap.h"
#include "image/metrics.h"

namespace pf::client {

// Exposure (stops) that maps the log-average luminance of the lit pixels of `image` to middle grey 0.18
// (the key value of Reinhard et al. 2002, "Photographic tone reproduction", eq. 1 and 2): the same for
// every image of a report, so brightness differences between algorithms stay visible. 0 for a black
// image.
double autoExposure(const Bitmap &image);

struct Region {
    int x = 0, y = 0, size = 0;
};
// Up to `count` square regions of a grid of tiles (side about a fifth of the shorter image side), those
// with the largest total error summed over `maps` (all of one size): where the algorithms differ most.
std::vector<Region> regionsOfLargestError(const std::vector<ErrorMap> &maps, int count);

// The pixels of `region` (inside the image) as an image of their own.
Bitmap crop(const Bitmap &image, const Region &region);

}  // namespace pf::client
