#include "integrators/pssmlt.h"

#include "scene/scene.h"

namespace pf {

PSSMLT::PSSMLT(const Properties &props) : PrimarySampleIntegrator(props) {
    if (!props.getBool("bidirectional", true))
        props.fail("bidirectional", "PSSMLT over the unidirectional path tracer is not implemented");
}

PrimarySampleIntegrator::ChainSetup PSSMLT::setup(const Scene &scene, const ChainTask &task, const ChainSeed &,
                                                  const Vec2 &raster, PCG32 &) const {
    const Film &film = scene.sensor().film();
    const Vec2 size(film.cropWidth(), film.cropHeight());
    ChainSetup s;
    s.psi = [this, &scene, size](Sampler &u, SplatList &out) {
        const Vec2 unit = u.next2D(), position(unit.x * size.x, unit.y * size.y);
        bdpt().evaluate(
            scene, u, position,
            [&](const StrategySample &x) {
                out.push_back({x.raster, x.value});
            },
            {}, minDepth());
    };
    s.prefix = {raster.x / size.x, raster.y / size.y};
    // The target's normalization constant is b̂, the sum over all depths.
    for (double l : task.depthLuminance) s.normalization += l;
    return s;
}

}  // namespace pf
