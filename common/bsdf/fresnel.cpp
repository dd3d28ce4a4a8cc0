#include "bsdf/fresnel.h"

#include <cmath>

#include "bsdf/quadrature.h"

namespace pf {

double fresnelDielectric(double cosThetaI, double eta, double &cosThetaT) {
    if (eta == 1.0) {
        cosThetaT = -cosThetaI;
        return 0.0;
    }
    // Snell's law with the ratio eta_i / eta_t of the side the light comes from over the other side.
    const double scale = cosThetaI > 0 ? 1.0 / eta : eta;
    const double cosThetaTSqr = 1.0 - (1.0 - cosThetaI * cosThetaI) * scale * scale;
    if (cosThetaTSqr <= 0.0) {
        cosThetaT = 0.0;
        return 1.0;
    }
    const double cosI = std::abs(cosThetaI), cosT = std::sqrt(cosThetaTSqr);
    // s- and p-polarized amplitude ratios written with eta_t / eta_i = 1 / scale (pbrt-v3 eq. 8.2),
    // multiplied through by eta_i so that only the ratio enters.
    const double rs = (cosI - cosT / scale) / (cosI + cosT / scale);
    const double rp = (cosI / scale - cosT) / (cosI / scale + cosT);
    cosThetaT = cosThetaI > 0 ? -cosT : cosT;
    return 0.5 * (rs * rs + rp * rp);
}

double fresnelDielectric(double cosThetaI, double eta) {
    double cosThetaT;
    return fresnelDielectric(cosThetaI, eta, cosThetaT);
}

namespace {

double fresnelConductorChannel(double cosThetaI, double eta, double k) {
    // pbrt-v3 §8.2.1 (after Born & Wolf): a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2).
    const double cos2 = cosThetaI * cosThetaI, sin2 = 1.0 - cos2, sin4 = sin2 * sin2;
    const double t0 = eta * eta - k * k - sin2;
    const double a2pb2 = std::sqrt(t0 * t0 + 4.0 * eta * eta * k * k);
    const double a = std::sqrt(std::max(0.0, 0.5 * (a2pb2 + t0)));
    const double t1 = a2pb2 + cos2, t2 = 2.0 * a * cosThetaI;
    const double rs = (t1 - t2) / (t1 + t2);
    const double t3 = a2pb2 * cos2 + sin4, t4 = t2 * sin2;
    const double rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5 * (rs + rp);
}

}  // namespace

Spectrum fresnelConductor(double cosThetaI, const Spectrum &eta, const Spectrum &k) {
    const double c = clamp(cosThetaI, -1.0, 1.0);
    return {fresnelConductorChannel(c, eta.r, k.r), fresnelConductorChannel(c, eta.g, k.g),
            fresnelConductorChannel(c, eta.b, k.b)};
}

double fresnelDiffuseReflectance(double eta) {
    // Below the critical cosine muC (only when eta < 1) the reflectance is 1, which contributes
    // muC^2. Above it, F has a square-root kink at muC; the substitution mu = muC + (1 - muC) s^2
    // makes the integrand smooth so that Gauss-Legendre converges quickly.
    const double muC = eta < 1.0 ? std::sqrt(1.0 - eta * eta) : 0.0;
    const double upper = integrateUnitInterval(
        [&](double s) {
            const double mu = muC + (1.0 - muC) * s * s;
            return 2.0 * fresnelDielectric(mu, eta) * mu * 2.0 * (1.0 - muC) * s;
        },
        32);
    return muC * muC + upper;
}

Vec3 refract(const Vec3 &wi, const Vec3 &m, double eta, double cosThetaT) {
    const double scale = cosThetaT < 0 ? 1.0 / eta : eta;
    return m * (dot(wi, m) * scale + cosThetaT) - wi * scale;
}

}  // namespace pf
