#include "bsdf/factories.h"

namespace pf {

PluginTable bsdfPlugins() {
    return {
        {"diffuse", createDiffuseBSDF},
        {"dielectric", createDielectricBSDF},
        {"thindielectric", createThinDielectricBSDF},
        {"roughdielectric", createRoughDielectricBSDF},
        {"conductor", createConductorBSDF},
        {"roughconductor", createRoughConductorBSDF},
        {"plastic", createPlasticBSDF},
        {"roughplastic", createRoughPlasticBSDF},
        {"twosided", createTwoSidedBSDF},
        {"ward", createWardBSDF},
        {"mask", createMaskBSDF},
        {"bumpmap", createBumpMapBSDF},
        {"null", createNullBSDF},
    };
}

}  // namespace pf
