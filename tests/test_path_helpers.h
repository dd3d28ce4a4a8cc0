// Helpers of the tests of path-space mutations (test_detailed_balance, test_portal): random complete paths
// from BDPT and a sampler that replays recorded numbers (for finite differences of a mutation's sampler).
#pragma once
#include <algorithm>
#include <vector>

#include "core/rng.h"
#include "core/sampler.h"
#include "integrators/bdpt.h"
#include "path/mutation.h"

namespace pf::test {

// The longest paths tested: the scene's maxDepth, at most 6 edges.
inline int maxVertices(const Scene &scene) {
    const int64_t depth = scene.integratorProperties().getInt("maxDepth", -1);
    return static_cast<int>(depth < 0 ? 7 : std::min<int64_t>(depth, 6) + 1);
}

// Complete paths as BDPT's strategies produce them (no Russian roulette), with nonzero contribution, from
// raster positions uniform over a res x res film.
inline std::vector<MutablePath> bdptPaths(const Scene &scene, size_t count, int res) {
    Properties props(ObjectKind::Integrator, "bdpt", {});
    props.set("maxDepth", Properties::Type::Integer, int64_t(maxVertices(scene) - 1), {});
    props.set("rrDepth", Properties::Type::Integer, int64_t(100), {});
    const BDPT bdpt(props);
    std::vector<MutablePath> paths;
    for (uint64_t sample = 0; paths.size() < count && sample < 100000; ++sample) {
        IndependentSampler sampler(17, sample, 0);
        const Vec2 raster(sampler.next1D() * res, sampler.next1D() * res);
        bdpt.evaluate(scene, sampler, raster, [&](const StrategySample &x) {
            if (paths.size() < count && x.weight > 0 && chainContribution(scene, *x.path).luminance() > 0)
                paths.emplace_back(*x.path);
        });
    }
    return paths;
}

// Replays a recorded list of numbers (then fresh ones), and records what it hands out.
class ReplaySampler final : public Sampler {
public:
    explicit ReplaySampler(std::vector<double> numbers, uint64_t seed = 0)
        : numbers_(std::move(numbers)), rng_(seed, 3) {}
    double next1D() override {
        if (next_ == numbers_.size()) numbers_.push_back(rng_.nextDouble());
        return numbers_[next_++];
    }
    const std::vector<double> &numbers() const { return numbers_; }

private:
    std::vector<double> numbers_;
    size_t next_ = 0;
    PCG32 rng_;
};

}  // namespace pf::test
