// Mitsuba 0.6's "envmap" emitter: an environment given as a latitude-longitude image. Orientation as in
// Mitsuba: a local direction v maps to u = atan2(v.x, -v.z) / (2 pi) (wrapped into [0, 1)) and
// v = acos(v.y) / pi, so +y is up, the image's top row is the zenith, and its horizontal centre looks
// along +z. Each pixel is a constant-radiance patch (no interpolation), which makes the map that is seen
// exactly the map that is sampled.
//
// Importance sampling (pbrt-v3 §14.2.4): a piecewise-constant 2D distribution over (u, v) with weights
// luminance * sin(theta at the row centre); the solid-angle density is p(u, v) / (2 pi^2 sin theta).
#include <cmath>

#include "core/distribution.h"
#include "emitter/endpoint.h"
#include "emitter/environment.h"
#include "image/bitmap.h"
#include "scene/plugins.h"

namespace pf {

namespace {

class EnvMapEmitter final : public EnvironmentEmitter {
public:
    EnvMapEmitter(const Properties &props, const LoadContext &ctx)
        : EnvironmentEmitter(rigidTransform(props, "toWorld")) {
        configureCommon(props);
        scale_ = props.getFloat("scale", 1.0);
        if (!(scale_ > 0)) props.fail("scale", "must be positive");
        // Mitsuba keeps a MIP-map cache file for large maps; the map is used at full resolution here and
        // nothing is cached, but scenes that set the flag still load.
        props.getBool("cache", false);
        loadMap(props, ctx);
        buildDistribution(props);
    }

protected:
    Spectrum radianceLocal(const Vec3 &v) const override {
        const Vec2 uv = directionToUV(v);
        return map_.get(column(uv.x), row(uv.y)) * scale_;
    }

    Vec3 sampleLocal(const Vec2 &u, double &pdf) const override {
        double pdfUV = 0;
        const Vec2 uv = dist_.sample(u, &pdfUV);
        const double theta = kPi * uv.y, phi = 2.0 * kPi * uv.x;
        const double sinTheta = std::sin(theta);
        pdf = sinTheta > 0 ? pdfUV / (2.0 * kPi * kPi * sinTheta) : 0.0;
        return {std::sin(phi) * sinTheta, std::cos(theta), -std::cos(phi) * sinTheta};
    }

    double pdfLocal(const Vec3 &v) const override {
        const double sinTheta = std::hypot(v.x, v.z);
        if (!(sinTheta > 0)) return 0.0;
        return dist_.pdf(directionToUV(v)) / (2.0 * kPi * kPi * sinTheta);
    }

    // Exact integral of the piecewise-constant map: each pixel spans 2 pi / W in phi and
    // cos(theta0) - cos(theta1) in cos theta.
    Spectrum integratedRadiance() const override {
        Spectrum sum(0.0);
        for (int y = 0; y < map_.height; ++y) {
            const double band = std::cos(kPi * y / map_.height) - std::cos(kPi * (y + 1) / map_.height);
            Spectrum rowSum(0.0);
            for (int x = 0; x < map_.width; ++x) rowSum += map_.get(x, y);
            sum += rowSum * band;
        }
        return sum * (2.0 * kPi / map_.width * scale_);
    }

private:
    static Vec2 directionToUV(const Vec3 &v) {
        double u = std::atan2(v.x, -v.z) * kInvTwoPi;
        if (u < 0) u += 1.0;
        // atan2 rather than acos(v.y): acos loses half the digits near the poles.
        return {u, std::atan2(std::hypot(v.x, v.z), v.y) * kInvPi};
    }
    int column(double u) const { return std::min(static_cast<int>(u * map_.width), map_.width - 1); }
    int row(double v) const { return std::min(static_cast<int>(v * map_.height), map_.height - 1); }

    // Mitsuba's `gamma`: 0 (default) = decide by file type (EXR linear, PNG/JPEG sRGB), -1 = sRGB curve,
    // any positive value = a pure power law.
    void loadMap(const Properties &props, const LoadContext &ctx) {
        const std::string path = ctx.resolve(props, "filename");
        const double gamma = props.getFloat("gamma", 0.0);
        if (!(gamma == 0 || gamma == -1 || gamma > 0))
            props.fail("gamma", "must be 0 (automatic), -1 (sRGB) or a positive exponent");
        map_ = readImage(path, gamma == 0);
        if (gamma != 0)
            for (float &c : map_.rgb)
                c = static_cast<float>(gamma < 0 ? srgbToLinear(c) : std::pow(std::max(0.0f, c), gamma));
        if (map_.width <= 0 || map_.height <= 0) props.fail("filename", "the environment map is empty");
    }

    void buildDistribution(const Properties &props) {
        std::vector<double> weights(static_cast<size_t>(map_.width) * map_.height);
        for (int y = 0; y < map_.height; ++y) {
            const double sinTheta = std::sin(kPi * (y + 0.5) / map_.height);
            for (int x = 0; x < map_.width; ++x) {
                const Spectrum s = map_.get(x, y);
                if (!s.isValid()) props.fail("filename", "the environment map has negative or non-finite pixels");
                weights[static_cast<size_t>(y) * map_.width + x] = s.luminance() * sinTheta;
            }
        }
        dist_ = Distribution2D(weights, static_cast<size_t>(map_.width), static_cast<size_t>(map_.height));
        double total = 0;
        for (double w : weights) total += w;
        // Mitsuba refuses a black map too: there would be nothing to sample.
        if (!(total > 0)) props.fail("filename", "the environment map is completely black");
    }

    Bitmap map_;
    double scale_ = 1.0;
    Distribution2D dist_;
};

}  // namespace

std::shared_ptr<Object> createEnvMapEmitter(const Properties &props, const LoadContext &ctx) {
    return std::make_shared<EnvMapEmitter>(props, ctx);
}

}  // namespace pf
