// The cases of the media agreement tests (test_mept_media.cpp and test_long_mept_media.cpp): MEPT as `erpt` with
// the manifold perturbation (and with it the medium-distance perturbation and medium chains, their defaults) in
// place of Veach's perturbations, every path left to the chains; MEMLT with its default mutations.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "test_mlt_common.h"

namespace pf::test {

struct MediaCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const MediaCase &c, std::ostream *os) { *os << c.scene; }
    std::string scene;
    int maxDepth;   // longest paths of chains and reference
    int block = 8;  // block size (16 at 16 x 16: the whole image, for a scene too noisy for smaller ones)
    std::string reference = "bdpt";
    int budget = 8;  // mept's seeds per pixel
    int chains = 4;  // mept's numChains: bursts per pixel on average
    // mept's manifoldGlossyAngle in degrees: larger, medium vertices join chains more often (manifold_perturbation.h).
    int glossyAngle = 1;
};

inline std::vector<std::pair<std::string, std::string>> meptParams(const MediaCase &c) {
    return {{"directSamples", "-1"},
            {"lensPerturbation", "false"},
            {"causticPerturbation", "false"},
            {"multiChainPerturbation", "false"},
            {"manifoldPerturbation", "true"},
            {"numChains", std::to_string(c.chains) + ".0"},
            {"manifoldGlossyAngle", std::to_string(c.glossyAngle) + ".0"}};
}

inline std::vector<std::pair<std::string, std::string>> memltParams(int res) {
    return {{"directSamples", "-1"}, {"luminanceSamples", std::to_string(res * res * 8)}};
}

// `base` (a set-up of test_mlt_common.h) with the case's budget, depth, blocks and reference.
inline ConvergenceSetup mediaSetup(const MediaCase &c, ConvergenceSetup base = {}) {
    base.budget = c.budget;
    base.maxDepth = c.maxDepth;
    base.block = c.block;
    base.reference = c.reference;
    return base;
}

inline std::string caseName(const MediaCase &c) {
    return gtestName(c.scene) + "_" + c.reference + "_depth" + std::to_string(c.maxDepth) +
           (c.glossyAngle != 1 ? "_dtheta" + std::to_string(c.glossyAngle) : "");
}

}  // namespace pf::test
