// Film and reconstruction-filter plugins with Mitsuba 0.6's parameters (src/films/hdrfilm.cpp,
// ldrfilm.cpp, src/librender/film.cpp, src/rfilters/*.cpp).
//
// What is used: the size and crop window, highQualityEdges, the filter; hdrfilm's pixelFormat (rgb,
// rgba, luminance, luminanceAlpha) and componentFormat (float16, float32) for the EXR; ldrfilm's
// tonemapMethod, gamma, exposure, key and burn (image/tonemap.h) and pixelFormat for the PNG beside it.
// fileFormat is recorded. pathfarm's EXR stays float32 unless componentFormat is given (Mitsuba's default
// is float16): its renders feed `diff` and `compare`. Accepted as Mitsuba does and not honoured: hdrfilm's
// xyz/xyza (written as rgb/rgba) and uint32 (written as float32), banner and attachLog. Mitsuba's
// render-time annotations (metadata['..'], label[..]) are not accepted.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <initializer_list>

#include "image/film.h"
#include "scene/plugins.h"

namespace pf {

namespace {

// Mitsuba compares string parameter values case-insensitively (boost::to_lower_copy).
std::string lowercase(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

std::string getChoice(const Properties &props, const std::string &name, const std::string &def,
                      std::initializer_list<const char *> allowed) {
    const std::string value = lowercase(props.getString(name, def));
    std::string list;
    for (const char *a : allowed) {
        if (value == a) return value;
        list += std::string(list.empty() ? "" : ", ") + a;
    }
    props.fail(name, "'" + value + "' is not one of: " + list);
}

// Mitsuba's pixelFormat names (lowercase); xyz is written as rgb (not honoured, see above).
PixelFormat pixelFormat(const std::string &name) {
    if (name == "luminance") return PixelFormat::Luminance;
    if (name == "luminancealpha") return PixelFormat::LuminanceAlpha;
    if (name == "rgba" || name == "xyza") return PixelFormat::RGBA;
    return PixelFormat::RGB;
}

class ConfiguredFilm final : public Film {
public:
    ConfiguredFilm(const Properties &props, bool hdr) {
        hdr_ = hdr;
        readGeometry(props);
        highQualityEdges_ = props.getBool("highQualityEdges", false);
        props.getBool("banner", true);
        if (hdr) {
            fileFormat_ = getChoice(props, "fileFormat", "openexr", {"openexr", "rgbe", "pfm"});
            // Mitsuba 0.6 in RGB mode rejects the spectrum* formats; the multichannel lists of
            // hdrfilm are not supported here.
            exrFormat_.pixels = pixelFormat(
                getChoice(props, "pixelFormat", "rgb", {"luminance", "luminancealpha", "rgb", "rgba", "xyz", "xyza"}));
            if (getChoice(props, "componentFormat", "float32", {"float16", "float32", "uint32"}) == "float16")
                exrFormat_.component = ComponentFormat::Float16;
            props.getBool("attachLog", true);
        } else {
            fileFormat_ = getChoice(props, "fileFormat", "png", {"png", "jpeg", "jpg"});
            if (fileFormat_ == "jpg") fileFormat_ = "jpeg";
            pngPixels_ =
                pixelFormat(getChoice(props, "pixelFormat", "rgb", {"luminance", "luminancealpha", "rgb", "rgba"}));
            if (getChoice(props, "tonemapMethod", "gamma", {"gamma", "reinhard"}) == "reinhard")
                toneMap_.method = ToneMap::Method::Reinhard;
            gamma_ = props.getFloat("gamma", -1.0);
            if (gamma_ != -1.0 && !(gamma_ > 0)) props.fail("gamma", "must be -1 (sRGB) or positive");
            // 2^100 already saturates any radiance a float holds; larger values only overflow.
            exposure_ = props.getFloat("exposure", 0.0);
            if (std::abs(exposure_) > 100) props.fail("exposure", "must lie in [-100, 100] stops");
            toneMap_.key = props.getFloat("key", 0.18);
            if (!(toneMap_.key > 0)) props.fail("key", "must be positive");
            toneMap_.burn = props.getFloat("burn", 0.0);
            if (!(toneMap_.burn >= 0 && toneMap_.burn <= 1)) props.fail("burn", "must lie in [0, 1]");
            toneMap_.gamma = gamma_;
            toneMap_.exposure = exposure_;
        }
        readFilter(props);
    }

private:
    // Film::Film of Mitsuba 0.6: the crop window defaults to the whole film and must lie inside it.
    void readGeometry(const Properties &props) {
        const int64_t w = props.getInt("width", 768), h = props.getInt("height", 576);
        const std::string range = " must lie in [1, " + std::to_string(kMaxSide) + "]";
        if (w < 1 || w > kMaxSide) props.fail("width", std::to_string(w) + range);
        if (h < 1 || h > kMaxSide) props.fail("height", std::to_string(h) + range);
        if (w * h > kMaxPixels)
            props.fail("height", std::to_string(w) + "x" + std::to_string(h) + " exceeds " +
                                     std::to_string(kMaxPixels) + " pixels");
        const int64_t cx = props.getInt("cropOffsetX", 0), cy = props.getInt("cropOffsetY", 0);
        if (cx < 0 || cx >= w)
            props.fail("cropOffsetX", std::to_string(cx) + " lies outside the film width " + std::to_string(w));
        if (cy < 0 || cy >= h)
            props.fail("cropOffsetY", std::to_string(cy) + " lies outside the film height " + std::to_string(h));
        const int64_t cw = props.getInt("cropWidth", w), ch = props.getInt("cropHeight", h);
        if (cw < 1 || cw > w - cx)
            props.fail("cropWidth", "crop window [" + std::to_string(cx) + ", " + std::to_string(cx + cw) +
                                        ") does not fit in the film width " + std::to_string(w));
        if (ch < 1 || ch > h - cy)
            props.fail("cropHeight", "crop window [" + std::to_string(cy) + ", " + std::to_string(cy + ch) +
                                         ") does not fit in the film height " + std::to_string(h));
        width_ = static_cast<int>(w);
        height_ = static_cast<int>(h);
        cropX_ = static_cast<int>(cx);
        cropY_ = static_cast<int>(cy);
        cropW_ = static_cast<int>(cw);
        cropH_ = static_cast<int>(ch);
    }

    // One nested rfilter; Mitsuba's default is a Gaussian of standard deviation 0.5 for both films.
    void readFilter(const Properties &props) {
        const auto filters = props.children(ObjectKind::RFilter);
        if (filters.size() > 1) props.fail("a film takes at most one nested rfilter");
        if (filters.empty()) {
            filter_ = std::make_shared<GaussianFilter>();
            return;
        }
        filter_ = std::dynamic_pointer_cast<ReconstructionFilter>(filters.front());
        if (!filter_) props.fail("the nested rfilter is not a reconstruction filter");
    }
};

std::string number(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

// Reads a filter's size parameter, of which the radius is `radiusPerUnit` times; radii beyond
// kMaxFilterRadius are refused (see rfilter.h).
double getRadius(const Properties &props, const std::string &name, double def, double radiusPerUnit) {
    const double v = props.getFloat(name, def);
    if (!(v > 0) || v * radiusPerUnit > kMaxFilterRadius)
        props.fail(name, "gives a filter radius of " + number(v * radiusPerUnit) + " pixels; it must lie in (0, " +
                             number(kMaxFilterRadius) + "]");
    return v;
}

}  // namespace

PluginTable filmPlugins() {
    return {
        {"hdrfilm", [](const Properties &p, const LoadContext &) { return std::make_shared<ConfiguredFilm>(p, true); }},
        {"ldrfilm",
         [](const Properties &p, const LoadContext &) { return std::make_shared<ConfiguredFilm>(p, false); }},
    };
}

PluginTable rfilterPlugins() {
    return {
        {"box", [](const Properties &p,
                   const LoadContext &) { return std::make_shared<BoxFilter>(getRadius(p, "radius", 0.5, 1.0)); }},
        {"tent", [](const Properties &, const LoadContext &) { return std::make_shared<TentFilter>(); }},
        {"gaussian",
         [](const Properties &p, const LoadContext &) {
             return std::make_shared<GaussianFilter>(getRadius(p, "stddev", 0.5, 4.0));
         }},
        {"mitchell",
         [](const Properties &p, const LoadContext &) {
             return std::make_shared<MitchellNetravaliFilter>(p.getFloat("B", 1.0 / 3.0), p.getFloat("C", 1.0 / 3.0));
         }},
        // Catmull-Rom is the Mitchell-Netravali cubic with B = 0, C = 1/2 (Mitsuba's catmullrom.cpp).
        {"catmullrom",
         [](const Properties &, const LoadContext &) { return std::make_shared<MitchellNetravaliFilter>(0.0, 0.5); }},
        {"lanczos",
         [](const Properties &p, const LoadContext &) {
             const int64_t lobes = p.getInt("lobes", 3);
             if (lobes < 1 || lobes > kMaxFilterRadius)
                 p.fail("lobes", "must lie in [1, " + number(kMaxFilterRadius) + "]");
             return std::make_shared<LanczosSincFilter>(static_cast<int>(lobes));
         }},
    };
}

}  // namespace pf
