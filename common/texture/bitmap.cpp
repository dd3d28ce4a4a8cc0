// Mitsuba 0.6's bitmap texture (src/textures/bitmap.cpp with the lookups of include/mitsuba/render/
// mipmap.h), evaluated at the full resolution.
//
// Parameters: filename (PNG, JPEG, BMP, Targa, Radiance RGBE .hdr or OpenEXR), gamma, filterType, maxAnisotropy, cache,
// wrapMode / wrapModeU / wrapModeV, channel, uoffset, voffset, uscale, vscale.
//
// Filtering: Mitsuba pre-filters with EWA or trilinear MIP-mapping when ray differentials are available
// and otherwise evaluates its full-resolution level bilinearly. pathfarm traces no ray differentials, so
// "ewa" (the default), "trilinear" and "bilinear" all mean bilinear interpolation of the full image, which
// is what Mitsuba itself does for rays without differentials; "nearest" picks the texel containing uv.
// maxAnisotropy and cache only concern the MIP map and are accepted and ignored.
//
// Layout: texel (i, j) is centred at uv = ((i + 0.5) / width, (j + 0.5) / height) and row j = 0 is the
// first row of the file (the top of the picture), as in Mitsuba 0.6's MIPMap.
#include "image/bitmap.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "scene/plugins.h"
#include "texture/texture.h"

namespace pf {

namespace {

enum class Wrap { Repeat, Mirror, Clamp, Zero, One };

std::string lowercase(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

// Mitsuba's parseWrapMode, including its aliases black (= zero) and white (= one).
Wrap parseWrap(const Properties &props, const std::string &name, const std::string &def) {
    const std::string s = lowercase(props.getString(name, def));
    if (s == "repeat") return Wrap::Repeat;
    if (s == "mirror") return Wrap::Mirror;
    if (s == "clamp") return Wrap::Clamp;
    if (s == "zero" || s == "black") return Wrap::Zero;
    if (s == "one" || s == "white") return Wrap::One;
    props.fail(name, "unknown wrap mode '" + s + "' (repeat, mirror, clamp, zero, one)");
}

// Mitsuba's Bitmap::setGamma followed by conversion to linear: -1 is the sRGB curve, 1 linear,
// anything else a pure power law.
double decode(double v, double gamma) {
    if (gamma == -1.0) return srgbToLinear(v);
    if (gamma == 1.0) return v;
    return std::copysign(std::pow(std::abs(v), gamma), v);
}

class BitmapTexture final : public Texture {
public:
    BitmapTexture(Bitmap image, Wrap wrapU, Wrap wrapV, bool nearest, const UVMapping &map)
        : img_(std::move(image)), wrapU_(wrapU), wrapV_(wrapV), nearest_(nearest), map_(map) {
        Spectrum sum(0.0);
        max_ = Spectrum(-kInfinity);
        for (int y = 0; y < img_.height; ++y)
            for (int x = 0; x < img_.width; ++x) {
                const Spectrum t = img_.get(x, y);
                sum += t;
                max_ = Spectrum(std::max(max_.r, t.r), std::max(max_.g, t.g), std::max(max_.b, t.b));
            }
        avg_ = sum / (static_cast<double>(img_.width) * img_.height);
    }

    Spectrum eval(const Intersection &its) const override {
        const Vec2 uv = map_.apply(its.uv);
        if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return Spectrum(0.0);  // Mitsuba: NaN lookup -> 0
        if (nearest_) return texel(toInt(std::floor(uv.x * img_.width)), toInt(std::floor(uv.y * img_.height)));
        const Cell c = cell(uv);
        return (c.t00 * (1 - c.dx) + c.t10 * c.dx) * (1 - c.dy) + (c.t01 * (1 - c.dx) + c.t11 * c.dx) * c.dy;
    }

    // Exact derivative of the bilinear interpolant inside a texel cell (Mitsuba's evalGradientBilinear),
    // chained through the uv scale; zero for nearest lookups, which are piecewise constant.
    void evalGradient(const Intersection &its, Spectrum &dfdu, Spectrum &dfdv) const override {
        const Vec2 uv = map_.apply(its.uv);
        if (nearest_ || !std::isfinite(uv.x) || !std::isfinite(uv.y)) {
            dfdu = dfdv = Spectrum(0.0);
            return;
        }
        const Cell c = cell(uv);
        dfdu = ((c.t10 - c.t00) * (1 - c.dy) + (c.t11 - c.t01) * c.dy) * (img_.width * map_.scale.x);
        dfdv = ((c.t01 - c.t00) * (1 - c.dx) + (c.t11 - c.t10) * c.dx) * (img_.height * map_.scale.y);
    }

    Spectrum average() const override { return avg_; }
    Spectrum maximum() const override { return max_; }

private:
    // The four texels around a lookup and the lookup's position between their centres.
    struct Cell {
        Spectrum t00, t10, t01, t11;
        double dx, dy;
    };

    Cell cell(const Vec2 &uv) const {
        const double x = uv.x * img_.width - 0.5, y = uv.y * img_.height - 0.5;
        const double fx = std::floor(x), fy = std::floor(y);
        const int ix = toInt(fx), iy = toInt(fy);
        return {texel(ix, iy), texel(ix + 1, iy), texel(ix, iy + 1), texel(ix + 1, iy + 1), x - fx, y - fy};
    }

    // Texel coordinates beyond +-2^30 carry no position information left in a double texture
    // coordinate; clamping them keeps the int arithmetic of the wrap modes defined.
    static int toInt(double v) { return static_cast<int>(clamp(v, -1073741824.0, 1073741824.0)); }

    // Mitsuba's MIPMap::evalTexel: out-of-range indices are wrapped per axis, or the lookup returns the
    // constant 0 or 1 for the zero/one modes.
    static bool wrapIndex(int &i, int n, Wrap mode) {
        if (i >= 0 && i < n) return true;
        switch (mode) {
            case Wrap::Repeat:
                i = ((i % n) + n) % n;
                return true;
            case Wrap::Clamp:
                i = std::clamp(i, 0, n - 1);
                return true;
            case Wrap::Mirror:
                i = ((i % (2 * n)) + 2 * n) % (2 * n);
                if (i >= n) i = 2 * n - 1 - i;
                return true;
            case Wrap::Zero:
            case Wrap::One:
                return false;
        }
        return false;
    }

    Spectrum texel(int x, int y) const {
        if (!wrapIndex(x, img_.width, wrapU_)) return Spectrum(wrapU_ == Wrap::One ? 1.0 : 0.0);
        if (!wrapIndex(y, img_.height, wrapV_)) return Spectrum(wrapV_ == Wrap::One ? 1.0 : 0.0);
        return img_.get(x, y);
    }

    Bitmap img_;
    Wrap wrapU_, wrapV_;
    bool nearest_;
    UVMapping map_;
    Spectrum avg_, max_;
};

}  // namespace

std::shared_ptr<Object> createBitmapTexture(const Properties &props, const LoadContext &ctx) {
    const std::string path = ctx.resolve(props, "filename");
    const std::string filter = lowercase(props.getString("filterType", "ewa"));
    if (filter != "ewa" && filter != "trilinear" && filter != "bilinear" && filter != "nearest")
        props.fail("filterType", "unknown filter type '" + filter + "' (ewa, trilinear, bilinear, nearest)");
    const double maxAnisotropy = props.getFloat("maxAnisotropy", 20.0);
    if (!(maxAnisotropy >= 1)) props.fail("maxAnisotropy", "must be at least 1");
    props.getBool("cache", false);
    // wrapMode sets both axes; it is checked on its own so that an error names the parameter written.
    parseWrap(props, "wrapMode", "repeat");
    const std::string wrap = props.getString("wrapMode", "repeat");
    const Wrap wrapU = parseWrap(props, "wrapModeU", wrap), wrapV = parseWrap(props, "wrapModeV", wrap);
    const std::string channel = lowercase(props.getString("channel", ""));
    if (!channel.empty() && channel != "r" && channel != "g" && channel != "b")
        props.fail("channel", "'" + channel + "' is not one of r, g, b (alpha channels are not loaded)");
    const UVMapping map(props);

    // Without `gamma` the file's own encoding applies (readImage: PNG, JPEG, BMP and Targa are sRGB, EXR
    // and Radiance RGBE linear); with it, the stored values are decoded with the given curve, EXR
    // included, as Mitsuba's Bitmap::setGamma does.
    const bool hasGamma = props.has("gamma");
    const double gamma = props.getFloat("gamma", -1.0);
    if (gamma != -1.0 && !(gamma > 0)) props.fail("gamma", "must be -1 (sRGB) or positive");
    Bitmap img = readImage(path, !hasGamma);
    if (hasGamma && gamma != 1.0)
        for (float &v : img.rgb) v = static_cast<float>(decode(v, gamma));
    if (!channel.empty()) {
        const int c = channel == "r" ? 0 : (channel == "g" ? 1 : 2);
        for (size_t i = 0; i < img.rgb.size(); i += 3) img.rgb[i] = img.rgb[i + 1] = img.rgb[i + 2] = img.rgb[i + c];
    }
    return std::make_shared<BitmapTexture>(std::move(img), wrapU, wrapV, filter == "nearest", map);
}

}  // namespace pf
