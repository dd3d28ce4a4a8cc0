// The portal-based path perturbation (Otsu, Hanika & Dachsbacher, "Portal-Based Path Perturbation for
// Metropolis Light Transport", §4; ALGORITHMS.md §7.2; SMS_PORTAL_NOTES.md §2): for a path that crosses a
// portal (scene/portal.h) on an edge x_i x_{i+1} other than the camera's first, the point p where that edge
// crosses the portal stays fixed and the edge turns about it: a new direction w* around the old one, with
// the lens perturbation's truncated 1 / theta kernel (the angle's density 1 / (theta ln(r2 / r1)), uniform
// azimuth; §4.4 eq. 5), is traced from p both ways to new x*_i and x*_{i+1}, which are connected to the
// unchanged x_{i-1} and x_{i+2}. The crossing taken is the first one counted from the sensor (the one
// nearest the sensor on that edge when it crosses several portals), so that the move is deterministic.
//
// Applicable when x_i and x_{i+1} are non-specular surface vertices (x_0: an emitter node a ray can hit,
// an area light or the environment), x_{i-1} and x_{i+2} non-specular (they are reconnected), and the
// crossing edge lies in vacuum. The proposal is rejected when a ray leaves the scene (the environment
// only ends the path's first edge), meets a specular or index-matched surface, a reconnection is blocked,
// or y's first portal crossing is not the same edge through the same point (then the reverse move does
// not exist: T(y -> x) = 0, which the reference code never checks).
//
// Density (§4.5 eq. 10, with the correction of SMS_PORTAL_NOTES.md §2.2). With p a pass-through vertex the
// move is a bijection of (p, w) with p kept (a delta in the portal's area measure, which cancels in the
// acceptance since the reverse move keeps the same p). The line measure gives
//     G(x_i, x_{i+1}) dA(x_i) dA(x_{i+1}) = |cos theta_p| dA(p) dw,
// theta_p the angle between w and the portal's normal, so in the area measure of the two new vertices
//     T(x -> y) = K(w* | w) G(y_i, y_{i+1}) / |cos theta_p(w*)|,
// K the solid-angle density of the direction kernel. The paper's code leaves out |cos theta_p|, which biases
// the chain towards grazing crossings (test_portal shows it). All vertices involved are non-specular, so the
// area measure is the chains' canonical one (path/mutation.h).
#pragma once
#include "path/perturbation.h"

namespace pf {

// Where a path crosses a portal first, counted from the sensor and skipping the camera's edge: the edge
// x_i x_{i+1} (edge = i), the portal's index in Scene::portals() and the crossing point; edge = -1 if none.
struct PortalCrossing {
    int edge = -1, portal = -1;
    Vec3 point;
};
PortalCrossing firstPortalCrossing(const Scene &scene, const PathView &x);

class PortalPerturbation final : public Mutation {
public:
    // The paper's angles r1 = 2^-8 and r2 = 2^-4 radians by default (portalR1, portalR2).
    PortalPerturbation(const Scene &scene, double r1, double r2);
    MutationType type() const override { return MutationType::Portal; }
    bool applies(const PathView &x) const override;
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;

    // Turns x's crossing edge about its crossing point into direction w (from the light side to the sensor
    // side) and reconnects: y as sample() makes it for that w; false when the move is rejected.
    bool turn(const Scene &scene, Sampler &sampler, const MutablePath &x, const PortalCrossing &crossing, const Vec3 &w,
              MutablePath &y) const;

private:
    const Scene &scene_;
    ReciprocalKernel kernel_;
};

}  // namespace pf
