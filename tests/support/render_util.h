// Helpers for integration tests: write a scene to a temporary file, load it, render it, and compute
// image statistics with confidence intervals.
#pragma once
#include <memory>
#include <string>

#include "image/bitmap.h"
#include "integrators/integrator.h"
#include "scene/scene.h"

namespace pf::test {

// A fresh directory under the build tree for this test's files, unique to this process.
std::string tempDir(const std::string &name);
// Writes `xml` to dir/name and returns the path.
std::string writeFile(const std::string &dir, const std::string &name, const std::string &contents);

struct RenderOutput {
    Bitmap image;
    RenderStats stats;
};
// Loads `xml` (written to a temporary file) and renders it with the named integrator.
RenderOutput renderXml(const std::string &xml, const std::string &integrator, int64_t spp, uint64_t seed = 1,
                       int threads = 0);

// Mean and standard error of one channel (or the luminance, channel = -1) over a pixel rectangle,
// treating pixels as independent samples of the same mean (valid for images that are uniform in
// expectation).
struct MeanCI {
    double mean = 0, stderr_ = 0;
    size_t n = 0;
};
MeanCI regionMean(const Bitmap &img, int x0, int y0, int x1, int y1, int channel = -1);

}  // namespace pf::test
