// A float RGB(A) image in memory: what films develop into, what EXR/PNG read and write, and what
// bitmap textures and environment maps load.
#pragma once
#include <map>
#include <string>
#include <vector>

#include "core/spectrum.h"

namespace pf {

struct Bitmap {
    int width = 0, height = 0;
    std::vector<float> rgb;  // row-major, 3 floats per pixel, linear
    std::map<std::string, std::string> metadata;

    Bitmap() = default;
    Bitmap(int w, int h) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, 0.0f) {}
    Spectrum get(int x, int y) const {
        const size_t i = (static_cast<size_t>(y) * width + x) * 3;
        return {rgb[i], rgb[i + 1], rgb[i + 2]};
    }
    void set(int x, int y, const Spectrum &s) {
        const size_t i = (static_cast<size_t>(y) * width + x) * 3;
        rgb[i] = static_cast<float>(s.r);
        rgb[i + 1] = static_cast<float>(s.g);
        rgb[i + 2] = static_cast<float>(s.b);
    }
};

// Image I/O. Readers throw SceneError naming the file on any failure (missing, corrupt, truncated,
// unsupported). EXR via OpenEXR (half, float or uint channels R, G, B, or a luminance channel Y); PNG
// (8 or 16 bit), JPEG, BMP and Targa via stb_image, with the sRGB transfer function removed when `srgb`
// is true; Radiance RGBE (.hdr) via stb_image, linear whatever `srgb` says. Alpha channels are not loaded.
Bitmap readEXR(const std::string &path);

// Mitsuba's pixelFormat (hdrfilm, ldrfilm) and componentFormat (hdrfilm) as the writers honour them.
// Luminance is Y = 0.2127 R + 0.7152 G + 0.0722 B (Rec. 709, Spectrum::luminance). pathfarm does not
// track coverage, so an alpha channel is written as 1 (every pixel covered).
enum class PixelFormat { RGB, RGBA, Luminance, LuminanceAlpha };
enum class ComponentFormat { Float16, Float32 };
struct EXRFormat {
    PixelFormat pixels = PixelFormat::RGB;
    ComponentFormat component = ComponentFormat::Float32;
};
// Channels R, G, B (A) or Y (A), half or float; metadata as string attributes.
void writeEXR(const std::string &path, const Bitmap &img, const EXRFormat &format = {});
Bitmap readLDR(const std::string &path, bool srgb);
// Tonemaps linear RGB to 8 bits (image/tonemap.h) and writes a PNG with 1-4 channels.
struct ToneMap;
void writePNG(const std::string &path, const Bitmap &img, const ToneMap &toneMap,
              PixelFormat pixels = PixelFormat::RGB);
// The same with the `gamma` method: exposure in stops, then clamp and the transfer curve, gamma = -1 the
// sRGB curve, any other positive value a pure power 1/gamma (ldrfilm's `gamma`).
void writePNG(const std::string &path, const Bitmap &img, double exposure = 0.0, double gamma = -1.0);
// Dispatch on extension or content (.exr or the EXR magic number -> readEXR; otherwise readLDR).
Bitmap readImage(const std::string &path, bool srgbForLDR);

}  // namespace pf
