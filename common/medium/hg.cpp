// Mitsuba 0.6 "hg": the Henyey-Greenstein phase function (Henyey & Greenstein 1941) with mean cosine g,
// forward scattering for g > 0. Both directions point away from the scattering point (scene/medium.h), so
// the scattering angle theta is the angle between -wi (the propagation direction) and wo:
//     p(wi, wo) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^{3/2}),  cos theta = -dot(wi, wo).
// Sampling inverts the CDF of cos theta exactly (pbrt-v3 §15.2.3), so sample() returns weight 1.
#include "core/frame.h"
#include "medium/media.h"

namespace pf {

namespace {

double hgDensity(double g, double cosTheta) {
    const double denom = 1.0 + g * g - 2.0 * g * cosTheta;
    return kInvFourPi * (1.0 - g * g) / (denom * std::sqrt(denom));
}

class HGPhase final : public PhaseFunction {
public:
    explicit HGPhase(double g) : g_(g) {}

    double eval(const Vec3 &wi, const Vec3 &wo) const override { return hgDensity(g_, -dot(wi, wo)); }
    double pdf(const Vec3 &wi, const Vec3 &wo) const override { return eval(wi, wo); }
    double sample(const Vec3 &wi, Vec3 &wo, double &pdf, const Vec2 &u) const override {
        const double cosTheta = hgSampleCosine(g_, u.x);
        const double sinTheta = safeSqrt(1.0 - cosTheta * cosTheta);
        const double phi = 2.0 * kPi * u.y;
        wo = Frame(-wi).toWorld(Vec3(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta));
        pdf = hgDensity(g_, cosTheta);
        return 1.0;
    }
    double meanCosine() const override { return g_; }

private:
    double g_;
};

}  // namespace

// With a = 1 - g + 2 g u, the textbook inverse (1 + g^2 - ((1 - g^2) / a)^2) / (2 g) simplifies to the
// expression below once the factor 2 g common to numerator and denominator is cancelled.
double hgSampleCosine(double g, double u) {
    const double a = 1.0 - g + 2.0 * g * u;
    const double mu = (2.0 * u * (1.0 + g * g) * (1.0 - g + g * u) - (1.0 - g) * (1.0 - g)) / (a * a);
    return clamp(mu, -1.0, 1.0);
}

double hgQuantileCosine(double g, double q) {
    const double ag = std::abs(g), s = 1.0 + g * g;
    const double denom = 1.0 + ag - 2.0 * ag * q;
    return clamp(((1.0 + ag) * (1.0 + ag) - 2.0 * (1.0 + ag) * s * q + 2.0 * ag * s * q * q) / (denom * denom), -1.0,
                 1.0);
}

// Mitsuba's default g is 0.8; it must lie strictly inside (-1, 1), where the density is finite.
std::shared_ptr<Object> createHGPhase(const Properties &props, const LoadContext &) {
    const double g = props.getFloat("g", 0.8);
    if (!(g > -1.0 && g < 1.0)) props.fail("g", "must lie strictly between -1 and 1");
    return std::make_shared<HGPhase>(g);
}

}  // namespace pf
