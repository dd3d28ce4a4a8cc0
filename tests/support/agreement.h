// Agreement of two image integrators on a scene: per-block means of images rendered with independent seeds.
// Each seed's image is an independent estimate, so the seed-to-seed spread of a block mean gives its standard
// error, whatever the correlations between pixels (light tracing splats one light path into several pixels).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "integrators/integrator.h"
#include "scene/scene.h"

namespace pf::test {

struct Edit {
    std::string from, to;
};

// A shared scene (scenes/<name>) with a box reconstruction filter: light tracing splats into the pixel it hits
// without a filter, so a comparison with the path tracer needs the same one-pixel footprint on both sides.
// `edits` are applied to the XML (each must match); the scene's other files are linked next to the edited copy.
// The film is resized to res x res (crop window reset), or left as the edited file has it if res <= 0.
std::unique_ptr<Scene> loadSharedScene(const std::string &name, int res, const std::vector<Edit> &edits = {});

struct BlockStats {
    std::vector<double> mean, stderr_;  // per block and channel, then the whole image's luminance
};

// Block means over `seeds` renders of `spp` samples per pixel (seeds 7919 (k + 1), one thread).
BlockStats blockStats(const Scene &scene, const Integrator &integrator, int block, int seeds, int spp);

// Block means of an integrator and of a reference must agree within 5 combined standard errors (with 32 seeds: a
// Student t with 31 degrees of freedom, so that a few hundred comparisons raise a false alarm with probability
// under 1%), and the errors must be small enough for that to mean something: the median block error under 3% of
// its mean. The whole image's luminance is compared too.
void expectAgreement(const BlockStats &reference, const BlockStats &tested, const std::string &what);

}  // namespace pf::test
