// Veach's lens subpath mutation (Veach & Guibas 1997; Veach 1997 ch. 11): replaces the lens subpath
// of the form [^S]S*E, the camera end of the path up to and including its first non-specular vertex x_b,
// by a new one. A new sensor walk starts at a uniformly chosen raster position (Veach stratifies these
// over the image; independent positions keep the chain's tasks independent of each other), crosses as many
// specular vertices as before and is connected to the unchanged x_{b-1}. It applies where the lens
// perturbation does, and moves the path to any part of the image in one step; T is the density of the
// new sensor walk. Mitsuba 0.6 dropped it; pathfarm keeps Veach's full set.
#pragma once
#include "path/mutation.h"

namespace pf {

class LensSubpathMutation final : public Mutation {
public:
    MutationType type() const override { return MutationType::LensSubpath; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;
};

}  // namespace pf
