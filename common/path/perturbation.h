// What Veach's perturbations share (Veach & Guibas 1997; Veach 1997 ch. 11; ALGORITHMS.md
// §4.1-4.2): the truncated reciprocal kernels that choose their step sizes, the sizes themselves, and
// the propagation of a perturbed direction through a chain of ideal specular vertices, keeping each one's
// lobe. Perturbations keep the path's configuration (its length and its sequence of specular and
// non-specular vertices, and the kind of each specular lobe): a proposal that changes it is rejected on the
// spot, which is symmetric because the reverse move would have to change it back.
#pragma once
#include "path/mutation.h"

namespace pf {

// A length r in [lo, hi] with density 1 / (r ln(hi / lo)) (ALGORITHMS.md §4.1), used as an image-plane
// offset (the lens perturbation) or as the angle between the old and the new direction (the caustic and
// multi-chain perturbations). Both kernels are symmetric: the density of moving by an offset or an angle
// does not depend on the direction of the move.
class ReciprocalKernel {
public:
    ReciprocalKernel(double lo, double hi);
    double lo() const { return lo_; }
    double hi() const { return hi_; }
    double sample(double u) const;
    double pdf(double r) const;
    // A planar offset of length r and uniform angle (two numbers), and its density per unit area.
    Vec2 sampleOffset(const Vec2 &u) const;
    double offsetPdf(const Vec2 &offset) const;
    // A unit direction at angle r from `axis` with uniform azimuth (two numbers), and its density per unit
    // solid angle.
    Vec3 sampleDirection(const Vec3 &axis, const Vec2 &u) const;
    double directionPdf(const Vec3 &axis, const Vec3 &d) const;

private:
    double lo_, hi_, logRatio_;
};

// Veach's step sizes (Veach 1997 ch. 11): image-plane offsets from r1 = 0.1 pixel to the radius r2 of a
// disk covering 5% of the image (Mitsuba's minJump and coveredArea), and the angle one pixel subtends at
// the camera, which converts them into angles.
struct PerturbationScale {
    explicit PerturbationScale(const Scene &scene);
    double r1 = 0.1, r2 = 0;
    double radiansPerPixel = 0;
    double filmArea = 0;  // pixels of the crop window, over which raster positions are uniform
};

// The unit vector from one vertex towards another.
Vec3 unitDirection(const PathVertex &from, const PathVertex &to);
// The direction of the ray that PathVertex::perturb traces from `from` to reach `to`. Rays leave surfaces
// from an origin offset along the normal (Scene::spawnRay); perturbation angles are measured there, so
// that the density of a sampled direction is evaluated for exactly that direction, also for the small
// angles at which the offset would otherwise matter.
Vec3 rayDirection(const Scene &scene, const PathVertex &from, const PathVertex &to);

// Traces direction d from y's vertex `from` towards vertex `to` (the emitter walk, mode Importance, goes
// up; the sensor walk down), through the specular vertices that x has strictly between them, each with the
// same kind of Dirac lobe as in x. Fills y's vertices and edges on the way, up to vertex `to`, which must be
// a scattering vertex of the same type as x's (a surface also stands in for an emitter node at index 0, to
// be cast by the caller). False when the configuration changes or the ray leaves the scene (y then holds
// part of the attempt and is not to be used). With held > 0, vertex `to` is a medium vertex of a manifold
// chain (ALGORITHMS.md §6.7): it is placed at distance `held` from its predecessor along the propagated
// direction instead of by free-flight sampling (placeHeld()).
bool propagate(const Scene &scene, Sampler &sampler, TransportMode mode, const PathView &x, MutablePath &y, int from,
               int to, Vec3 d, double held = 0.0);
// The medium that point p lies in, seen from vertex `from` along the straight line to it: from's medium towards p,
// switched at every index-matched boundary on the way (edge.h); nullptr when p lies in vacuum or behind a surface
// that is not index-matched.
const Medium *mediumAt(const Scene &scene, const PathVertex &from, const Vec3 &p);
// The medium vertex at distance `held` from vertex `from` along unit direction d, reached by the walk of `mode`,
// and its edge (transmittance through every medium on the way, densities) from `from`; false when a surface that
// is not index-matched lies in between. A crossing does not bend the edge, so the held length is the distance
// between the two vertices and the vertex lies in the medium beyond the last crossing (mediumAt()).
bool placeHeld(const Scene &scene, TransportMode mode, const PathVertex &from, const Vec3 &d, double held,
               PathEdge &edge, PathVertex &succ);

// The factor that turns the solid-angle density of the direction leaving vertex `from` into the density
// of vertex `to` when that direction is propagated as above: for each step, the successor's cosine over
// the squared distance and the edge's free-flight probability. Dirac vertices on the way count with lobe
// probability 1, since propagation keeps their lobe (the pseudo-measure of mutation.h).
double propagationJacobian(const PathView &y, int from, int to, TransportMode mode);

// The structure the lens and multi-chain perturbations act on (Veach 1997 ch. 11): read from the sensor,
// the first edge x_{b-1} x_b with two non-specular ends (b = 0: x_0 is an area emitter that a perturbed
// ray can land on), and the number of specular chains crossed before it (1: x_b is the first non-specular
// vertex, the lens perturbation's case; more: the multi-chain perturbation's). chains = 0 when there is no
// such edge.
struct SensorChains {
    int b = -1, chains = 0;
};
SensorChains sensorChains(const PathView &x);

// Veach's lens perturbation followed by the multi-chain cascade: moves the raster position by an offset
// drawn from `offset`, traces the new camera ray through the first specular chain, and at every further
// non-specular vertex before x_b perturbs the direction towards the next chain by an angle drawn from
// `angle` (null for the lens perturbation, which crosses one chain); then connects the new x_b to x_{b-1}.
// `chains` is sensorChains(x).
bool sampleSensorCascade(const Scene &scene, Sampler &sampler, const ReciprocalKernel &offset,
                         const ReciprocalKernel *angle, const MutablePath &x, const SensorChains &chains,
                         MutablePath &y);
// Its density T(x -> y) (sensor walk: already canonical), zero if y does not have x's structure or the
// perturbation does not apply to x (one chain without `angle`, several with it).
double sensorCascadeDensity(const Scene &scene, const ReciprocalKernel &offset, const ReciprocalKernel *angle,
                            const PerturbationScale &scale, const PathView &x, const PathView &y);

}  // namespace pf
