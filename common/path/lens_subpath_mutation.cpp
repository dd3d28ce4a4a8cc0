#include "path/lens_subpath_mutation.h"

#include "path/perturbation.h"

namespace pf {

bool LensSubpathMutation::applies(const PathView &x) const { return sensorChains(x).chains == 1; }

bool LensSubpathMutation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                 MutationRecord &record) const {
    const int n = x.length(), b = sensorChains(x).b;
    record = {b - 1, n, n - b};
    y.splice(x, b - 1, n, n - b);
    if (!extendWalk(scene, sampler, TransportMode::Radiance, y, n, n - b)) return false;
    // The same number of specular vertices before the new x_b.
    for (int i = b + 1; i < n - 1; ++i)
        if (!y.vertex(i).delta) return false;
    return connectJunction(scene, y, b - 1);
}

double LensSubpathMutation::density(const Scene &scene, const PathView &x, const PathView &y,
                                    const MutationRecord &) const {
    const SensorChains cx = sensorChains(x), cy = sensorChains(y);
    const int n = x.length();
    if (cx.chains != 1 || cy.chains != 1 || cx.b != cy.b || y.length() != n) return 0.0;
    // The regenerated vertices x_b .. x_{n-1} (walkDensity); buffers kept per thread, as a chain calls this twice per
    // step.
    thread_local std::vector<double> pFwd, pRev;
    evalDensities(scene, y, cx.b, n - 1, pFwd, pRev);
    return walkDensity(scene, y, cx.b - 1, 0, n, pFwd, pRev);
}

}  // namespace pf
