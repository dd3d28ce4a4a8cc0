// Factories of the BSDF plugins (Mitsuba 0.6 names and parameters), listed by bsdfPlugins() in
// bsdf_plugins.cpp. Each reads and validates its Properties and throws SceneError naming the bad
// parameter.
#pragma once
#include <memory>

#include "scene/plugins.h"

namespace pf {

std::shared_ptr<Object> createDiffuseBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createDielectricBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createThinDielectricBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createRoughDielectricBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createConductorBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createRoughConductorBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createPlasticBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createRoughPlasticBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createTwoSidedBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createWardBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createMaskBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createBumpMapBSDF(const Properties &props, const LoadContext &ctx);
std::shared_ptr<Object> createNullBSDF(const Properties &props, const LoadContext &ctx);

}  // namespace pf
