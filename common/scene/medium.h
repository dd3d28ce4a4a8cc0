// Participating media and phase functions ([TH ch. 3, 7]; ALGORITHMS.md §1.1). Shapes carry
// interior/exterior media; a shape with media and no BSDF is an index-matched (null) boundary. The
// sensor may sit inside a medium.
//
// Conventions: in the phase function both directions point away from the scattering point (Mitsuba's
// convention; the "arrow form" f(a->b->c) of §1.1 flips wi), so an isotropic medium has
// eval = 1/(4 pi) for every pair.
#pragma once
#include <memory>

#include "core/spectrum.h"
#include "core/vector.h"
#include "scene/object.h"

namespace pf {

class PhaseFunction : public Object {
public:
    virtual double eval(const Vec3 &wi, const Vec3 &wo) const = 0;
    virtual double pdf(const Vec3 &wi, const Vec3 &wo) const = 0;
    // Samples wo; returns eval/pdf (1 for perfectly importance-sampled phase functions).
    virtual double sample(const Vec3 &wi, Vec3 &wo, double &pdf, const Vec2 &u) const = 0;
    virtual double meanCosine() const = 0;
};

struct MediumSample {
    double t = 0;              // distance along the ray of the sampled interaction (ray.tmax if none)
    Vec3 p;                    // its position
    Spectrum transmittance;    // along [ray.tmin, t]
    Spectrum sigmaA, sigmaS;   // coefficients at p
    double pdfSuccess = 0;     // density per unit length of sampling an interaction at t (channel-averaged)
    double pdfSuccessRev = 0;  // the same for sampling from the other end of the segment
    double pdfFailure = 0;     // probability of sampling no interaction on the whole segment
    const class Medium *medium = nullptr;
};

class Medium : public Object {
public:
    // Free-flight sampling on the segment [ray.tmin, ray.tmax]. Returns true and fills ms for a medium
    // interaction before ray.tmax; returns false when the segment is crossed (ms.transmittance and
    // ms.pdfFailure then describe the whole segment).
    virtual bool sampleDistance(const Ray &ray, double u, MediumSample &ms) const = 0;
    // Transmittance exp(-sigma_t * length) on [ray.tmin, ray.tmax].
    virtual Spectrum evalTransmittance(const Ray &ray) const = 0;
    // Densities that sampleDistance would assign to the segment [ray.tmin, ray.tmax]: if `interaction`,
    // pdfSuccess/pdfSuccessRev for an interaction at either end; otherwise pdfFailure for crossing it.
    virtual void evalDistancePdf(const Ray &ray, bool interaction, MediumSample &ms) const = 0;
    virtual Spectrum sigmaS() const = 0;
    virtual Spectrum sigmaT() const = 0;
    const PhaseFunction &phase() const { return *phase_; }

protected:
    std::shared_ptr<PhaseFunction> phase_;
};

}  // namespace pf
