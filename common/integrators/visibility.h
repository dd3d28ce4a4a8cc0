// Visibility through index-matched surfaces and participating media. Surfaces whose BSDF has a Null
// lobe (the null BSDF, the transparent part of a mask or thin dielectric, the boundaries of
// index-matched media) let light pass unchanged in direction; a shadow ray must pass through them too,
// or next-event estimation would miss paths that BSDF sampling finds and the MIS combination would be
// biased. Media attenuate each segment by exp(-sigma_t * length) (ALGORITHMS.md §1.1: the tau in G).
#pragma once
#include "core/function_ref.h"
#include "core/spectrum.h"
#include "scene/intersection.h"
#include "scene/scene.h"

namespace pf {

class Medium;

// The walk behind transmittance() where it has surfaces to pass through or a medium to attenuate.
Spectrum walkedTransmittance(const Scene &scene, const Ray &ray, const Medium *medium, bool trackMedia);

// Fraction of light arriving along `ray` (tmax set to stop short of the target), starting in `medium`
// (nullptr = vacuum): zero if an opaque surface is in the way, otherwise the product of the Null-lobe
// transmittances of the surfaces crossed and of each segment's medium (crossing a medium's boundary switches
// media, mediumAfter). ray.d must be a unit vector, so that ray parameters are lengths. With trackMedia =
// false media are ignored (the `path` integrator). Inline for its common case, a plain occlusion query
// (nothing to pass through, no medium): `path` asks it at every vertex, and the call into the walk cost some
// 70 instructions a shadow ray (issue 17).
inline Spectrum transmittance(const Scene &scene, const Ray &ray, const Medium *medium, bool trackMedia = true) {
    if (!scene.hasPassThroughSurfaces() && !(trackMedia && medium)) return Spectrum(scene.occluded(ray) ? 0.0 : 1.0);
    return walkedTransmittance(scene, ray, medium, trackMedia);
}

// The same without media.
inline Spectrum transmittance(const Scene &scene, const Ray &ray) { return transmittance(scene, ray, nullptr, false); }

// Called for each surface a walk reaches, with the transmittance from the ray origin up to it.
using SurfaceVisitor = FunctionRef<void(const Intersection &its, const Spectrum &T)>;

// The walk behind transmittance(scene, ray, medium), for callers that also need the surfaces on the way
// (volpath collects the emission of every surface a sampled direction reaches). Calls visit at each
// surface reached before ray.tmax, the blocking one included; returns the transmittance to ray.tmax
// (infinite rays: out of the scene), or zero when a surface without a Null lobe is in the way.
// `firstHit`, if given, receives the first surface along the ray (invalid if none): the next vertex of a
// path that continues along it, so callers need not trace the same ray again.
Spectrum walkTransmittance(const Scene &scene, const Ray &ray, const Medium *medium, const SurfaceVisitor &visit,
                           bool trackMedia = true, Intersection *firstHit = nullptr);

// Null-lobe transmittance of the surface at `its` for a ray passing straight through it
// (0 for opaque surfaces, 1 for the null BSDF).
Spectrum nullTransmittance(const Intersection &its);

// The medium a ray is in after leaving the surface `its` in world direction d: a shape that bounds
// media (it has an interior or exterior medium: Mitsuba's isMediumTransition) switches to the medium on
// the side d points into; any other surface leaves `current` unchanged.
const Medium *mediumAfter(const Intersection &its, const Vec3 &d, const Medium *current);

// Radiance emitted towards `ref` by the surface `its` that `ray` (leaving ref) reached, or by the
// environment when its is invalid, weighted by the power heuristic against next-event estimation from
// ref for a direction drawn with solid-angle density dirPdf; a delta-sampled direction (which
// next-event estimation cannot produce) gets weight 1.
Spectrum misWeightedEmission(const Scene &scene, const Ray &ray, const Intersection &its, const Vec3 &ref,
                             double dirPdf, bool delta);

}  // namespace pf
