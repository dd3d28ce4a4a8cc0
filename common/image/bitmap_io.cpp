// Image file I/O: OpenEXR through the OpenEXR 3 C++ API, PNG, JPEG, BMP, Targa and Radiance RGBE (.hdr)
// through stb_image, PNG output through stb_image_write.
//
// Every failure on input becomes a SceneError naming the file: files come from user scene bundles and
// render outputs, and a bad one must never crash a worker. Formats are recognised by their magic
// numbers rather than by stb's chain of format probes, the chunk or segment structure of a PNG or JPEG
// is checked before stb decodes it (pngDefect, jpegDefect), and images above kMaxImagePixels are refused before any
// pixel memory is allocated. Outputs are written to a temporary file and renamed into place, so a crash never leaves a
// half-written image under the final name.
// clang-format off: the configuration macros must precede their headers.
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#define STBI_ONLY_BMP
#define STBI_ONLY_TGA
#define STBI_ONLY_HDR
#define STBI_NO_STDIO
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb_image_write.h>
// clang-format on

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <half.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <memory>

#include "core/error.h"
#include "image/bitmap.h"
#include "image/tonemap.h"

namespace pf {

namespace fs = std::filesystem;

namespace {

// Same bound as the film's: 2^28 pixels is a 16k x 16k texture (3 GiB as float RGB).
constexpr int64_t kMaxImagePixels = int64_t(1) << 28;
constexpr int64_t kMaxImageSide = int64_t(1) << 16;

[[noreturn]] void fail(const std::string &path, const std::string &msg) { throw SceneError({path, 0}, msg); }

void checkSize(const std::string &path, int64_t w, int64_t h) {
    if (w < 1 || h < 1 || w > kMaxImageSide || h > kMaxImageSide || w * h > kMaxImagePixels)
        fail(path, "image size " + std::to_string(w) + "x" + std::to_string(h) + " is empty or too large");
}

// Reads up to `limit` bytes. libstdc++ throws from inside a stream read on some I/O errors, so the
// read is guarded as well as checked.
std::vector<unsigned char> readFile(const std::string &path, size_t limit = std::numeric_limits<size_t>::max()) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) fail(path, "cannot open image file");
    const uintmax_t size = fs::file_size(path, ec);
    if (ec) fail(path, "cannot open image file: " + ec.message());
    try {
        std::ifstream in(path, std::ios::binary);
        std::vector<unsigned char> data(std::min<uintmax_t>(size, limit));
        in.read(reinterpret_cast<char *>(data.data()), static_cast<std::streamsize>(data.size()));
        if (!in) fail(path, "error while reading image file");
        return data;
    } catch (const std::ios_base::failure &e) {
        fail(path, std::string("error while reading image file: ") + e.what());
    }
}

bool startsWith(const std::vector<unsigned char> &data, std::initializer_list<unsigned char> magic) {
    return data.size() >= magic.size() && std::equal(magic.begin(), magic.end(), data.begin());
}

bool isEXR(const std::vector<unsigned char> &data) { return startsWith(data, {0x76, 0x2f, 0x31, 0x01}); }

bool isJPEG(const std::vector<unsigned char> &data) { return startsWith(data, {0xff, 0xd8, 0xff}); }

// Radiance's header starts "#?RADIANCE" or "#?RGBE" (Ward, Graphics Gems II, "Real pixels").
bool isRGBE(const std::vector<unsigned char> &data) {
    return startsWith(data, {'#', '?', 'R', 'A', 'D', 'I', 'A', 'N', 'C', 'E', '\n'}) ||
           startsWith(data, {'#', '?', 'R', 'G', 'B', 'E', '\n'});
}

// stb_image 2.27 decodes a flat (not run-length encoded) RGBE file that ends early as black pixels, so
// its length is checked first: the pixels follow the header's empty line and the resolution line, and a
// flat file holds 4 bytes per pixel (a run-length encoded scanline starts with 2, 2; stb checks those).
bool rgbeEndsEarly(const std::vector<unsigned char> &d, int64_t w, int64_t h) {
    const unsigned char blank[2] = {'\n', '\n'};
    auto it = std::search(d.begin(), d.end(), blank, blank + 2);
    if (it == d.end()) return true;
    it = std::find(it + 2, d.end(), '\n');
    if (it == d.end()) return true;
    const size_t start = static_cast<size_t>(it - d.begin()) + 1, left = d.size() - start;
    const bool rle = w >= 8 && w < 32768 && left >= 2 && d[start] == 2 && d[start + 1] == 2;
    return !rle && left < static_cast<size_t>(4 * w * h);
}

bool isBMP(const std::vector<unsigned char> &data) { return startsWith(data, {'B', 'M'}); }

// Targa has no magic number; its header's colour-map and image types must be ones stb decodes
// (uncompressed or RLE; colour-mapped, true-colour or grey).
bool isTarga(const std::vector<unsigned char> &data) {
    if (data.size() < 18 || data[1] > 1) return false;
    const unsigned type = data[2] & ~8u;
    return type >= 1 && type <= 3;
}

// Walks the marker segments of a JPEG (ITU-T T.81 Annex B) and checks what stb_image cannot be trusted
// with: stb 2.27 (Debian 12) does not bound the number of codes in a Huffman table (DHT) and writes
// past its tables for a table of more than 256 codes, and later releases decode a file that stops in
// the middle of a scan by padding it with zeros. So every DHT table must hold at most 256 codes, every
// segment must lie inside the file, and an end-of-image marker must follow the last scan. Returns why
// the file is rejected, or an empty string.
std::string jpegDefect(const std::vector<unsigned char> &d) {
    const size_t n = d.size();
    bool scanned = false;
    size_t pos = 2;  // after the start-of-image marker
    while (pos + 1 < n) {
        if (d[pos] != 0xff) return "bytes outside any segment";
        while (pos + 1 < n && d[pos + 1] == 0xff) ++pos;  // fill bytes before a marker
        if (pos + 1 >= n) break;
        const unsigned char marker = d[pos + 1];
        pos += 2;
        if (marker == 0xd9) return scanned ? "" : "no scan before the end-of-image marker";
        if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd7)) continue;  // markers without a segment
        if (pos + 2 > n) break;
        const size_t len = size_t(d[pos]) << 8 | d[pos + 1];
        if (len < 2 || pos + len > n) return "segment runs past the end of the file";
        if (marker == 0xc4) {
            for (size_t q = pos + 2; q < pos + len;) {
                if (q + 17 > pos + len) return "truncated Huffman table";
                size_t codes = 0;
                for (size_t i = 1; i <= 16; ++i) codes += d[q + i];
                if (codes > 256) return "Huffman table with more than 256 codes";
                q += 17 + codes;
                if (q > pos + len) return "truncated Huffman table";
            }
        }
        pos += len;
        if (marker == 0xda) {
            // Entropy-coded data runs to the next marker: 0xff followed by anything but a stuffed zero
            // or a restart marker.
            scanned = true;
            while (pos + 1 < n && !(d[pos] == 0xff && d[pos + 1] != 0 && (d[pos + 1] < 0xd0 || d[pos + 1] > 0xd7)))
                ++pos;
        }
    }
    return "file ends before the end-of-image marker";
}

// Walks the chunks of a PNG (ISO/IEC 15948, section 5.3: length, type, data, CRC) and checks what
// stb_image cannot be trusted with: it grows its buffer for the compressed data to each IDAT chunk's
// declared length before reading it, so a file of a few bytes that declares a 2 GiB chunk made it
// allocate 2 GiB (fuzz/fuzz_image.cpp). Every chunk must lie inside the file. Returns why the file is
// rejected, or an empty string.
std::string pngDefect(const std::vector<unsigned char> &d) {
    const size_t n = d.size();
    for (size_t pos = 8; pos < n;) {  // after the signature
        if (pos + 12 > n) return "chunk header runs past the end of the file";
        const size_t len = size_t(d[pos]) << 24 | size_t(d[pos + 1]) << 16 | size_t(d[pos + 2]) << 8 | d[pos + 3];
        if (len > n - pos - 12) return "chunk of " + std::to_string(len) + " bytes runs past the end of the file";
        if (std::string_view(reinterpret_cast<const char *>(&d[pos + 4]), 4) == "IEND") return "";
        pos += 12 + len;
    }
    return "file ends before the IEND chunk";
}

// Deleter for pixel buffers returned by stb_image.
struct StbFree {
    void operator()(void *p) const { stbi_image_free(p); }
};

// Writes through a temporary file that is renamed over `path` once complete.
template <typename WriteFn>
void writeAtomically(const std::string &path, WriteFn write) {
    const std::string tmp = path + ".partial";
    try {
        write(tmp);
        std::error_code ec;
        fs::rename(tmp, path, ec);
        if (ec) fail(path, "cannot write image file: " + ec.message());
    } catch (...) {
        std::error_code ignored;
        fs::remove(tmp, ignored);
        throw;
    }
}

void checkWritable(const std::string &path, const Bitmap &img) {
    if (img.width < 1 || img.height < 1) fail(path, "cannot write an empty image");
    if (img.rgb.size() != static_cast<size_t>(img.width) * static_cast<size_t>(img.height) * 3)
        fail(path, "image buffer does not match its size");
}

}  // namespace

Bitmap readEXR(const std::string &path) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) fail(path, "cannot open image file");
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header &header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        const int64_t w = int64_t(dw.max.x) - dw.min.x + 1, h = int64_t(dw.max.y) - dw.min.y + 1;
        checkSize(path, w, h);
        const Imf::ChannelList &channels = header.channels();
        const bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
        if (!rgb && !channels.findChannel("Y")) fail(path, "EXR file has neither R, G, B nor Y channels");

        Bitmap img(static_cast<int>(w), static_cast<int>(h));
        // Half and uint channels are converted to float by the library.
        Imf::FrameBuffer fb;
        constexpr size_t px = 3 * sizeof(float);
        char *base = reinterpret_cast<char *>(img.rgb.data());
        std::vector<float> grey;
        if (rgb) {
            fb.insert("R", Imf::Slice::Make(Imf::FLOAT, base, dw, px, px * w));
            fb.insert("G", Imf::Slice::Make(Imf::FLOAT, base + sizeof(float), dw, px, px * w));
            fb.insert("B", Imf::Slice::Make(Imf::FLOAT, base + 2 * sizeof(float), dw, px, px * w));
        } else {
            grey.resize(static_cast<size_t>(w * h));
            fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, grey.data(), dw, sizeof(float), sizeof(float) * w));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        for (size_t i = 0; i < grey.size(); ++i) img.rgb[3 * i] = img.rgb[3 * i + 1] = img.rgb[3 * i + 2] = grey[i];

        for (auto it = header.begin(); it != header.end(); ++it)
            if (const auto *s = dynamic_cast<const Imf::StringAttribute *>(&it.attribute()))
                img.metadata[it.name()] = s->value();
        return img;
    } catch (const SceneError &) {
        throw;
    } catch (const std::exception &e) {
        fail(path, std::string("cannot read EXR file: ") + e.what());
    }
}

namespace {

bool hasAlpha(PixelFormat f) { return f == PixelFormat::RGBA || f == PixelFormat::LuminanceAlpha; }
bool isGrey(PixelFormat f) { return f == PixelFormat::Luminance || f == PixelFormat::LuminanceAlpha; }

// The image's values in the pixel format's channel order, `channels` per pixel.
template <class T, class Convert>
std::vector<T> interleave(const Bitmap &img, PixelFormat f, int channels, const Convert &convert) {
    const size_t pixels = static_cast<size_t>(img.width) * static_cast<size_t>(img.height);
    std::vector<T> out(pixels * static_cast<size_t>(channels));
    for (size_t p = 0; p < pixels; ++p) {
        T *o = &out[p * static_cast<size_t>(channels)];
        const float *in = &img.rgb[3 * p];
        if (isGrey(f))
            o[0] = convert(Spectrum(in[0], in[1], in[2]).luminance());
        else
            for (int c = 0; c < 3; ++c) o[c] = convert(in[c]);
        if (hasAlpha(f)) o[channels - 1] = convert(1.0);
    }
    return out;
}

}  // namespace

void writeEXR(const std::string &path, const Bitmap &img, const EXRFormat &format) {
    checkWritable(path, img);
    const bool half = format.component == ComponentFormat::Float16;
    std::vector<const char *> names =
        isGrey(format.pixels) ? std::vector<const char *>{"Y"} : std::vector<const char *>{"R", "G", "B"};
    if (hasAlpha(format.pixels)) names.push_back("A");
    const int channels = static_cast<int>(names.size());
    // OpenEXR's Slice takes a non-const pointer but only reads through it when writing.
    const std::vector<float> floats =
        half ? std::vector<float>{}
             : interleave<float>(img, format.pixels, channels, [](double v) { return float(v); });
    const std::vector<Imath::half> halves =
        half ? interleave<Imath::half>(img, format.pixels, channels, [](double v) { return Imath::half(float(v)); })
             : std::vector<Imath::half>{};
    writeAtomically(path, [&](const std::string &tmp) {
        try {
            Imf::Header header(img.width, img.height);
            const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
            for (const char *c : names) header.channels().insert(c, Imf::Channel(type));
            for (const auto &[key, value] : img.metadata) header.insert(key, Imf::StringAttribute(value));
            Imf::FrameBuffer fb;
            const size_t size = half ? sizeof(Imath::half) : sizeof(float), px = size * static_cast<size_t>(channels);
            char *base = const_cast<char *>(half ? reinterpret_cast<const char *>(halves.data())
                                                 : reinterpret_cast<const char *>(floats.data()));
            const size_t row = px * static_cast<size_t>(img.width);
            for (int c = 0; c < channels; ++c)
                fb.insert(names[static_cast<size_t>(c)],
                          Imf::Slice(type, base + size * static_cast<size_t>(c), px, row));
            Imf::OutputFile out(tmp.c_str(), header);
            out.setFrameBuffer(fb);
            out.writePixels(img.height);
        } catch (const std::exception &e) {
            fail(path, std::string("cannot write EXR file: ") + e.what());
        }
    });
}

// PNG, JPEG, BMP and Targa hold 8 or 16-bit values, returned as [0, 1] floats and sRGB-decoded on request;
// Radiance RGBE holds linear radiance, returned as it is. The format is the file's magic number (Targa,
// which has none: the .tga extension and a header of a type stb decodes).
Bitmap readLDR(const std::string &path, bool srgb) {
    const std::vector<unsigned char> data = readFile(path);
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    const bool png = startsWith(data, {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'}), jpeg = isJPEG(data),
               rgbe = isRGBE(data), bmp = isBMP(data), tga = ext == ".tga" && !png && !jpeg && !rgbe && !bmp;
    const char *format = png ? "PNG" : jpeg ? "JPEG" : rgbe ? "Radiance RGBE" : bmp ? "BMP" : "Targa";
    if (!png && !jpeg && !rgbe && !bmp && !tga) fail(path, "not a PNG, JPEG, BMP, Targa or Radiance RGBE image");
    if (data.size() > static_cast<size_t>(std::numeric_limits<int>::max())) fail(path, "image file too large");
    const auto *bytes = data.data();
    const int len = static_cast<int>(data.size());
    // stb's own failure reason is only meaningful once the decoder of the right format has run; after
    // stbi_info it names whichever format was probed last.
    auto corrupt = [&](const std::string &detail) {
        fail(path, std::string("corrupt or truncated ") + format + " file" + detail);
    };
    if (png || jpeg)
        if (const std::string defect = png ? pngDefect(data) : jpegDefect(data); !defect.empty())
            corrupt(" (" + defect + ")");
    if (tga && !isTarga(data)) corrupt(" (not a Targa type stb decodes)");
    int w = 0, h = 0, n = 0;
    if (!stbi_info_from_memory(bytes, len, &w, &h, &n)) corrupt(" (unreadable header)");
    checkSize(path, w, h);

    Bitmap img(w, h);
    const size_t count = img.rgb.size();
    if (rgbe) {
        if (rgbeEndsEarly(data, w, h)) corrupt(" (pixel data ends early)");
        std::unique_ptr<float, StbFree> pixels(stbi_loadf_from_memory(bytes, len, &w, &h, &n, 3));
        if (!pixels) corrupt(std::string(": ") + stbi_failure_reason());
        std::copy(pixels.get(), pixels.get() + count, img.rgb.begin());
    } else if (stbi_is_16_bit_from_memory(bytes, len)) {
        std::unique_ptr<stbi_us, StbFree> pixels(stbi_load_16_from_memory(bytes, len, &w, &h, &n, 3));
        if (!pixels) corrupt(std::string(": ") + stbi_failure_reason());
        for (size_t i = 0; i < count; ++i) {
            const double v = pixels.get()[i] / 65535.0;
            img.rgb[i] = static_cast<float>(srgb ? srgbToLinear(v) : v);
        }
    } else {
        std::unique_ptr<stbi_uc, StbFree> pixels(stbi_load_from_memory(bytes, len, &w, &h, &n, 3));
        if (!pixels) corrupt(std::string(": ") + stbi_failure_reason());
        std::array<float, 256> lut;
        for (int i = 0; i < 256; ++i) lut[i] = static_cast<float>(srgb ? srgbToLinear(i / 255.0) : i / 255.0);
        for (size_t i = 0; i < count; ++i) img.rgb[i] = lut[pixels.get()[i]];
    }
    return img;
}

void writePNG(const std::string &path, const Bitmap &img, const ToneMap &t, PixelFormat pixels) {
    checkWritable(path, img);
    if (!std::isfinite(t.exposure) || !(t.gamma == -1.0 || t.gamma > 0) || !(t.key > 0) ||
        !(t.burn >= 0 && t.burn <= 1))
        fail(path, "invalid exposure, gamma, key or burn for PNG");
    // Grey formats tone-map the luminance; then the pixel format's channels of the display values, quantised.
    Bitmap grey;
    if (isGrey(pixels)) {
        grey = Bitmap(img.width, img.height);
        for (size_t p = 0; p < grey.rgb.size(); p += 3)
            grey.rgb[p] = grey.rgb[p + 1] = grey.rgb[p + 2] =
                static_cast<float>(Spectrum(img.rgb[p], img.rgb[p + 1], img.rgb[p + 2]).luminance());
    }
    Bitmap display(img.width, img.height);
    const std::vector<double> values = toneMap(isGrey(pixels) ? grey : img, t);
    std::transform(values.begin(), values.end(), display.rgb.begin(), [](double v) { return float(v); });
    const int channels = (isGrey(pixels) ? 1 : 3) + (hasAlpha(pixels) ? 1 : 0);
    const std::vector<unsigned char> bytes = interleave<unsigned char>(display, pixels, channels, [](double v) {
        return static_cast<unsigned char>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0));
    });
    writeAtomically(path, [&](const std::string &tmp) {
        if (!stbi_write_png(tmp.c_str(), img.width, img.height, channels, bytes.data(), img.width * channels))
            fail(path, "cannot write PNG file");
    });
}

void writePNG(const std::string &path, const Bitmap &img, double exposure, double gamma) {
    ToneMap t;
    t.exposure = exposure;
    t.gamma = gamma;
    writePNG(path, img, t);
}

Bitmap readImage(const std::string &path, bool srgbForLDR) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".exr") return readEXR(path);
    // Recognise EXR content under another name too, so that the error for a damaged file comes from
    // the right reader.
    return isEXR(readFile(path, 4)) ? readEXR(path) : readLDR(path, srgbForLDR);
}

}  // namespace pf
