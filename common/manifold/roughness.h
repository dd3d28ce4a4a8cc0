// The probabilistic classification of rough vertices in manifold exploration's glossy extension ([TR §5.2,
// A1], [TH §6.2, A1]; ALGORITHMS.md §6.6). A glossy vertex joins a specular chain (and is moved by the
// manifold walk on an offset manifold) with probability psi_spec, and stays a non-specular vertex (one the
// perturbation can start from or end at) otherwise. The probability compares the spread of the scattering
// lobe, an angle theta_q that a fraction q of the microfacet normals (or of the phase function's scattering
// angles) stay within, with the mean change dtheta of that angle under one perturbation: a lobe much wider
// than a step behaves diffusely, one much narrower specularly.
//
// The erratum (§6.6): [TR A1] and [TH A1] print
//     (1 - cos theta_q) / (1 - cos(theta_q + dtheta))
// and call it the specular probability, but it goes to 0 for smooth surfaces, which must always be
// specular. It is the *non*-specular probability (Mitsuba's nonspecularProbSurface), so psi_spec is one
// minus it. The classification is a heuristic: any function keeps the method unbiased as long as both
// transition directions use the same one, and this one reproduces the paper.
#pragma once

namespace pf {

// The q-quantile of the Beckmann-equivalent microfacet slope angle as [TR A1] prints it (and Mitsuba
// computes it): atan(-alpha^2 ln(1 - q)). The exact Beckmann quantile has sqrt(-ln(1 - q)) and alpha to
// the first power; the printed form is kept to reproduce the paper. alpha = infinity (diffuse) gives pi/2.
double beckmannQuantileAngle(double alpha, double q = 0.9);

// The q-quantile of the scattering angle of a Henyey-Greenstein phase function with mean cosine g
// ([TR A1]), measured from the direction of its lobe (forward for g >= 0, backward for g < 0). The
// median (q = 0.5) of g = 0.8 has cosine 0.944.
double hgQuantileAngle(double g, double q = 0.5);

// P_nonspec = (1 - cos theta_q) / (1 - cos(theta_q + dtheta)), with theta_q + dtheta capped at pi (as in
// Mitsuba), for a lobe of quantile angle thetaQ and a mean perturbation angle dtheta (radians).
double nonSpecularProbability(double thetaQ, double dtheta);
// psi_spec = 1 - P_nonspec (the erratum above).
double specularProbability(double thetaQ, double dtheta);

// The same for a surface of Beckmann-equivalent roughness alpha: 0 for ideal specular (alpha = 0) and
// 1 for diffuse (alpha = infinity) surfaces, which are never part of a chain.
double nonSpecularProbabilitySurface(double alpha, double dtheta);

}  // namespace pf
