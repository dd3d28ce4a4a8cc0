// The von Mises-Fisher distribution on the unit sphere ([TH A3]; ALGORITHMS.md §6.8), the direction kernel
// of the manifold perturbation (§6.5): f(w) = kappa / (4 pi sinh kappa) exp(kappa mu.w) around the mean
// direction mu. Manifold perturbations use concentrations up to kappa ~ 2 pi lambda^2 p ~ 1e9, where
// sinh overflows and the angular scale 1 / sqrt(kappa) is below what a float dot product resolves, so every
// formula here is the numerically stable one of §6.8, in double precision.
#pragma once
#include "core/vector.h"

namespace pf {

class VonMisesFisher {
public:
    // kappa >= 0 (0: the uniform density on the sphere).
    explicit VonMisesFisher(double kappa);
    // The concentration whose peak density f(mu) is `peak` (per steradian): the inverse of peakDensity(),
    // through Jakob's rational fit below kappa = 5 ([TH A3]; absolute error < 0.007 there) and
    // kappa = 2 pi peak above, where coth kappa = 1 to double precision. A peak below 1 / (4 pi) (flatter
    // than uniform) has no solution and gives the fit's floor, kappa = 1e-5.
    static VonMisesFisher fromPeakDensity(double peak);

    double kappa() const { return kappa_; }
    // The density per steradian of unit direction w around unit mean mu.
    double eval(const Vec3 &mu, const Vec3 &w) const;
    // The density as a function of u = 1 - mu.w, which callers that hold u exactly pass directly.
    double evalOneMinusCos(double u) const;
    // A direction around +z (u: two uniform numbers), and around mu.
    Vec3 sample(const Vec2 &u) const;
    Vec3 sample(const Vec3 &mu, const Vec2 &u) const;

    // f(mu) = kappa / (4 pi) (1 + coth kappa).
    static double peakDensity(double kappa);
    // E[mu.w] = coth kappa - 1 / kappa (Langevin's function A3), by its series near 0.
    static double meanCosine(double kappa);

private:
    double kappa_;
    double norm_;  // kappa / (2 pi (1 - e^{-2 kappa})), the density at mu divided by exp(0)
    double e2k_;   // e^{-2 kappa}
};

}  // namespace pf
