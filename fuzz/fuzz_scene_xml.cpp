// libFuzzer target: the Mitsuba XML loader on a scene file that can <include> a part, name a mesh, a
// texture and a spectrum file, and use <default>s and $-defines (the files the fixture writes beside it).
// Bad input must end in a SceneError naming file and line; any other exception, crash, leak or sanitizer
// report is a finding.
#include "core/error.h"
#include "fuzz_util.h"
#include "scene/scene.h"

namespace {

void writeFixture() {
    static bool done = false;
    if (done) return;
    done = true;
    const auto put = [](const std::string &name, const std::string &text) {
        pf::fuzz::writeInput(name, reinterpret_cast<const uint8_t *>(text.data()), text.size());
    };
    put("parts/light.xml", R"(<scene version="0.5.0"><default name="power" value="5"/>
<shape type="sphere"><float name="radius" value="0.2"/><emitter type="area"><spectrum name="radiance" value="$power"/></emitter></shape></scene>)");
    put("meshes/floor.obj", "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\nf 1 3 4\n");
    put("spectra/flat.spd", "400 0.5\n500 0.6\n600 0.7\n700 0.8\n");
}

// A scene that uses every file of the fixture: the included part, the mesh, the spectrum file, a
// <default> and the defines.
std::vector<std::string> seeds() {
    return {R"(<scene version="0.5.0"><default name="res" value="16"/>
<integrator type="path"><integer name="maxDepth" value="3"/></integrator>
<sensor type="perspective"><transform name="toWorld"><lookat origin="0, 1, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
<sampler type="independent"><integer name="sampleCount" value="$spp"/></sampler>
<film type="hdrfilm"><integer name="width" value="$res"/><integer name="height" value="$res"/></film></sensor>
<include filename="parts/light.xml"/>
<shape type="obj"><string name="filename" value="meshes/floor.obj"/>
<bsdf type="diffuse"><spectrum name="reflectance" filename="spectra/flat.spd"/></bsdf></shape>
</scene>)"};
}

}  // namespace

PATHFARM_FUZZ_SEEDS(seeds)

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    writeFixture();
    const std::string path = pf::fuzz::writeInput("scene.xml", data, size);
    try {
        const auto scene = pf::loadScene(path, {{"spp", "4"}, {"res", "8"}}, false);
    } catch (const pf::SceneError &) {
    }
    return 0;
}
