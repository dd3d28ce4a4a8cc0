#include "manifold/vmf.h"

#include <algorithm>

#include "core/frame.h"
#include "core/sincos.h"

namespace pf {

namespace {

// Below this concentration the density is uniform to double precision (kappa u <= 2e-12).
constexpr double kUniformKappa = 1e-12;

}  // namespace

VonMisesFisher::VonMisesFisher(double kappa) : kappa_(std::max(kappa, 0.0)) {
    e2k_ = std::exp(-2 * kappa_);
    // kappa / (2 pi (1 - e^{-2 kappa})) -> 1 / (4 pi) as kappa -> 0; -expm1 keeps the digits there.
    norm_ = kappa_ > kUniformKappa ? kappa_ / (2 * kPi * -std::expm1(-2 * kappa_)) : 1 / (4 * kPi);
}

VonMisesFisher VonMisesFisher::fromPeakDensity(double peak) {
    // g(5) = 5 / (4 pi) (1 + coth 5) ~ 0.795: above it coth kappa = 1 within 1e-4 and kappa = 2 pi c.
    if (peak > peakDensity(5.0)) return VonMisesFisher(2 * kPi * peak);
    const double c = peak;
    return VonMisesFisher(
        std::max(1e-5, (168.479 * c * c + 16.4585 * c - 2.39942) / (-1.12718 * c * c + 29.1433 * c + 1)));
}

double VonMisesFisher::evalOneMinusCos(double u) const {
    // f = kappa / (2 pi (1 - e^{-2 kappa})) exp(kappa (mu.w - 1)) ([TH A3], §6.8): no sinh to overflow.
    return kappa_ > kUniformKappa ? norm_ * std::exp(-kappa_ * u) : norm_;
}

double VonMisesFisher::eval(const Vec3 &mu, const Vec3 &w) const {
    // 1 - mu.w = |mu - w|^2 / 2 for unit vectors, without the cancellation of 1 - dot near the mean.
    return evalOneMinusCos((mu - w).lengthSquared() / 2);
}

Vec3 VonMisesFisher::sample(const Vec2 &u) const {
    // W = 1 + ln(xi + (1 - xi) e^{-2 kappa}) / kappa (§6.8, the form safe at xi = 0), kept as 1 - W.
    double oneMinusW;
    if (kappa_ > kUniformKappa) {
        const double xi = 1 - u.x;  // in (0, 1] for u.x in [0, 1)
        oneMinusW = -std::log(xi + (1 - xi) * e2k_) / kappa_;
    } else {
        oneMinusW = 2 * u.x;
    }
    oneMinusW = std::clamp(oneMinusW, 0.0, 2.0);
    const double sinTheta = std::sqrt(oneMinusW * (2 - oneMinusW));
    const SinCos phi = sinCos2Pi(u.y);
    return {sinTheta * phi.cos, sinTheta * phi.sin, 1 - oneMinusW};
}

Vec3 VonMisesFisher::sample(const Vec3 &mu, const Vec2 &u) const { return Frame(mu).toWorld(sample(u)); }

double VonMisesFisher::peakDensity(double kappa) {
    if (kappa <= kUniformKappa) return 1 / (4 * kPi);
    // kappa (1 + coth kappa) = 2 kappa / (1 - e^{-2 kappa}).
    return kappa / (2 * kPi * -std::expm1(-2 * kappa));
}

double VonMisesFisher::meanCosine(double kappa) {
    // coth k - 1/k cancels for small k; its series k/3 - k^3/45 + 2 k^5/945 is exact to 1e-13 below 1e-2.
    if (kappa < 1e-2) {
        const double k2 = kappa * kappa;
        return kappa * (1.0 / 3 - k2 / 45 + 2 * k2 * k2 / 945);
    }
    // coth k = (1 + e^{-2k}) / (1 - e^{-2k}).
    const double e = std::exp(-2 * kappa);
    return (1 + e) / -std::expm1(-2 * kappa) - 1 / kappa;
}

}  // namespace pf
