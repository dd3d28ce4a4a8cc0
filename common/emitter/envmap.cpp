// Mitsuba 0.6's "envmap" emitter: an environment given as a latitude-longitude image, in Mitsuba's
// orientation and importance-sampled by luminance (emitter/latlong_map.h).
#include <cmath>
#include <stdexcept>

#include "emitter/endpoint.h"
#include "emitter/environment.h"
#include "emitter/latlong_map.h"
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
        try {
            map_ = LatLongMap(loadMap(props, ctx));
        } catch (const std::invalid_argument &e) {
            props.fail("filename", e.what());
        }
    }

protected:
    Spectrum radianceLocal(const Vec3 &v) const override { return map_.eval(v) * scale_; }
    Vec3 sampleLocal(const Vec2 &u, double &pdf) const override { return map_.sample(u, pdf); }
    double pdfLocal(const Vec3 &v) const override { return map_.pdf(v); }
    Spectrum integratedRadiance() const override { return map_.integral() * scale_; }

private:
    // Mitsuba's `gamma`: 0 (default) = decide by file type (EXR and Radiance RGBE linear, PNG, JPEG, BMP
    // and Targa sRGB), -1 = sRGB curve,
    // any positive value = a pure power law.
    static Bitmap loadMap(const Properties &props, const LoadContext &ctx) {
        const std::string path = ctx.resolve(props, "filename");
        const double gamma = props.getFloat("gamma", 0.0);
        if (!(gamma == 0 || gamma == -1 || gamma > 0))
            props.fail("gamma", "must be 0 (automatic), -1 (sRGB) or a positive exponent");
        Bitmap map = readImage(path, gamma == 0);
        if (gamma != 0)
            for (float &c : map.rgb)
                c = static_cast<float>(gamma < 0 ? srgbToLinear(c) : std::pow(std::max(0.0f, c), gamma));
        return map;
    }

    LatLongMap map_;
    double scale_ = 1.0;
};

}  // namespace

std::shared_ptr<Object> createEnvMapEmitter(const Properties &props, const LoadContext &ctx) {
    return std::make_shared<EnvMapEmitter>(props, ctx);
}

}  // namespace pf
