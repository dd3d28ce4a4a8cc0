// The comparison of test_portal and test_long_portal: mlt with the portal perturbation in the mixture of
// Otsu et al. §5 (bidirectional 0.5, lens 0.25, portal 0.25) against BDPT and against mlt with the paper's
// mixture without it (bidirectional and lens, 0.5 each), by block means over independent renders (each with
// its own seeding, b̂ and chains), every path left to the chains.
#pragma once
#include <string>

#include "test_mlt_common.h"

namespace pf::test {

inline void expectPortalConvergence(const std::string &name, const ConvergenceSetup &s, int luminanceSamples) {
    const std::vector<std::pair<std::string, std::string>> paper = {
        {"directSamples", "-1"},
        {"luminanceSamples", std::to_string(luminanceSamples)},
        {"lensSubpathMutation", "false"},
        {"causticPerturbation", "false"},
        {"multiChainPerturbation", "false"}};
    auto withPortal = paper;
    withPortal.emplace_back("portalPerturbation", "true");
    auto scene = loadMLTTestScene(name, s.res, 4);
    const auto mlt = makeTestIntegrator(*scene, "mlt", withMaxDepth(paper, s.maxDepth));
    const auto portal = makeTestIntegrator(*scene, "mlt", withMaxDepth(withPortal, s.maxDepth));
    const BlockStats plain = blockStats(*scene, *mlt, s.block, s.seeds, s.budget, 2);
    const BlockStats portals = blockStats(*scene, *portal, s.block, s.seeds, s.budget, 2);
    const BlockStats &reference = bdptReference(name, *scene, s.block, s.seeds, s.referenceSpp, s.maxDepth);
    printAgreement(reference, portals, name + " mlt+portal vs bdpt");
    expectBlocksAgree(reference, portals, s.sigmas, s.maxMedianError, s.maxImageError, name + " vs bdpt");
    printAgreement(plain, portals, name + " mlt+portal vs mlt");
    expectBlocksAgree(plain, portals, s.sigmas, s.maxMedianError, s.maxImageError, name + " vs mlt");
    // The portal perturbation must have been used for the comparison to say anything about it.
    for (const MutationCount &c : chainStatistics(*scene, *portal, s.budget).counts)
        if (c.name == "portal") {
            std::printf("%s portal: %llu proposed, acceptance %.3f\n", name.c_str(),
                        static_cast<unsigned long long>(c.proposed),
                        static_cast<double>(c.accepted) / std::max(1.0, static_cast<double>(c.proposed)));
            EXPECT_GT(c.accepted, 1000u) << name;
        }
}

}  // namespace pf::test
