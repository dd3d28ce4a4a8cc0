// libFuzzer target: the image readers as bitmap textures and environment maps load them (readImage:
// EXR by its magic number, else PNG/JPEG through stb). Bad files must end in a SceneError.
#include "core/error.h"
#include "fuzz_util.h"
#include "image/bitmap.h"

namespace {

// A 4 x 3 image as EXR and as PNG, written by the renderer's own writers.
std::vector<std::string> seeds() {
    pf::Bitmap image;
    image.width = 4;
    image.height = 3;
    for (int i = 0; i < 4 * 3 * 3; ++i) image.rgb.push_back(static_cast<float>(i) / 36.0f);
    const std::string exr = pf::fuzz::workDir() + "/seed.exr", png = pf::fuzz::workDir() + "/seed.png";
    pf::writeEXR(exr, image);
    pf::writePNG(png, image);
    const auto read = [](const std::string &path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
    };
    return {'\0' + read(exr), '\1' + read(png)};
}

}  // namespace

PATHFARM_FUZZ_SEEDS(seeds)

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    // The extension only steers the dispatch: EXR content is recognised by its magic number anyway.
    const char *name = data[0] & 1 ? "image.png" : "image.exr";
    try {
        pf::readImage(pf::fuzz::writeInput(name, data + 1, size - 1), data[0] & 2);
    } catch (const pf::SceneError &) {
    }
    return 0;
}
