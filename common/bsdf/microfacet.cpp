#include "bsdf/microfacet.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "bsdf/bsdf_util.h"
#include "bsdf/quadrature.h"
#include "core/frame.h"
#include "core/sincos.h"
#include "texture/texture.h"

namespace pf {

namespace {

constexpr double kSqrtPi = 1.77245385090551602729;
constexpr double kMinAlpha = 1e-4;

// Inverse of the standard normal-like CDF (1 + erf(y)) / 2 = u, i.e. the y-slope of a Beckmann
// surface with alpha = 1 (slope density exp(-y^2) / sqrt(pi)). Giles' single-precision erfinv
// approximation (2010, "Approximating the erfinv function") gives the start; Newton steps on the
// erfc form, which keeps full relative precision in the tails, refine it to double precision.
double beckmannSlopeFromCdf(double u) {
    if (u > 0.5) return -beckmannSlopeFromCdf(1.0 - u);
    // Solve erfc(t) = 2u for t >= 0 (the slope is -t). Below 1e-16 the tail is cut: a probability
    // mass of 1e-16 cannot be resolved by any test and would otherwise produce an infinite slope.
    const double target = 2.0 * std::max(u, 1e-16);
    const double x = 1.0 - target;  // erf(t) = x
    double w = -std::log((1.0 - x) * (1.0 + x)), p;
    if (w < 5.0) {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = std::sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    double t = p * x;
    for (int i = 0; i < 3; ++i) t += (std::erfc(t) - target) / (2.0 / kSqrtPi * std::exp(-t * t));
    return -t;
}

// Visible slopes of the Beckmann surface with alpha = 1 seen from a direction with cot(theta) = a
// (Heitz & d'Eon 2014, §4 and appendix). The x-slope (towards the viewer's azimuth) has density
// proportional to (a - x) exp(-x^2) on x < a, whose CDF is
//     C(x) = [a sqrt(pi)/2 erfc(-x) + exp(-x^2)/2] / Z,  Z = C's numerator at x = a;
// it is inverted here by safeguarded Newton iteration (exact up to round-off; Mitsuba 0.6 uses an
// approximate inverse refined the same way). The y-slope is independent with density exp(-y^2)/sqrt(pi).
Vec2 sampleBeckmannVisibleSlopes(double cosTheta, double sinTheta, const Vec2 &u) {
    if (sinTheta < 1e-7) {
        // Normal incidence: all slopes are equally visible, a 2D Gaussian sampled in polar form.
        const double r = std::sqrt(-std::log(1.0 - u.x));
        const SinCos phi = sinCos2Pi(u.y);
        return {r * phi.cos, r * phi.sin};
    }
    const double a = cosTheta / sinTheta;
    const auto numerator = [a](double x) { return a * 0.5 * kSqrtPi * std::erfc(-x) + 0.5 * std::exp(-x * x); };
    const double scale = numerator(a), target = u.x * scale;
    // Beyond |x| = 7 the density is below exp(-49): the bracket ends there (or at a).
    double lo = -7.0, hi = std::min(a, 7.0);
    double x;
    if (numerator(lo) >= target) {
        x = lo;
    } else if (numerator(hi) <= target) {
        x = hi;
    } else {
        x = std::clamp(0.0, lo, hi);
        for (int i = 0; i < 100; ++i) {
            const double g = numerator(x) - target;
            // A residual at the precision of the target itself (its rounding and u's resolution, about 2^-53
            // of the scale) is a root: one more Newton step would move x by rounding noise only, and a step
            // that noise pushes onto the bracket's end would fall back to bisection for dozens of iterations.
            // Over incidence angles with uniform cos(theta), the loop took 15.8 iterations on average without
            // this test and takes 6.3 with it; the largest CDF error fell from 8.5e-14 to 1.2e-15.
            if (std::abs(g) <= 0x1p-50 * scale) break;
            if (g < 0)
                lo = x;
            else
                hi = x;
            const double dg = (a - x) * std::exp(-x * x);
            double next = dg > 0 ? x - g / dg : 0.5 * (lo + hi);
            if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
            const bool done = std::abs(next - x) < 1e-13 * std::max(1.0, std::abs(x));
            x = next;
            if (done || hi - lo < 1e-14) break;
        }
    }
    return {x, beckmannSlopeFromCdf(u.y)};
}

// Smith's Lambda for the isotropic Phong distribution D = (e + 2) / (2 pi) cos^e(theta_m), seen from
// a direction with cot(theta) = mu. With the slope marginal P2(q) = C (1 + q^2)^(-(e + 3) / 2),
//     C = (e + 2) / (2 sqrt(pi)) Gamma((e + 3) / 2) / Gamma((e + 4) / 2),
// Lambda = (1 / mu) \int_mu^inf (q - mu) P2(q) dq (Heitz 2014 eq. 72). With q = tan t the integrand
// becomes (sin t - mu cos t) cos^e t on [atan mu, pi/2], smooth and concentrated within a few
// 1 / sqrt(e + 1) of its start, where the Gauss-Legendre rule is applied. Mitsuba 0.6 instead uses the
// Beckmann function at the same alpha, which lets rough Phong surfaces reflect more than they receive
// at grazing angles.
double phongLambda(double e, double mu) {
    const double c =
        (e + 2.0) / (2.0 * kSqrtPi) * std::exp(std::lgamma(0.5 * (e + 3.0)) - std::lgamma(0.5 * (e + 4.0)));
    const double t0 = std::atan(mu), t1 = std::min(0.5 * kPi, t0 + 12.0 / std::sqrt(e + 1.0));
    const double integral = integrateUnitInterval(
        [&](double x) {
            const double t = t0 + x * (t1 - t0);
            return (std::sin(t) - mu * std::cos(t)) * std::pow(std::cos(t), e);
        },
        1);
    return c * integral * (t1 - t0) / mu;
}

std::string toLower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

std::shared_ptr<Texture> readAlpha(const Properties &props, const std::string &name) {
    std::shared_ptr<Texture> tex = props.getTexture(name, Spectrum(0.1));
    if (tex->isConstant() && tex->average().min() < 0) props.fail(name, "the roughness must be non-negative");
    return tex;
}

}  // namespace

MicrofacetDistribution::MicrofacetDistribution(MicrofacetType type, double alphaU, double alphaV, bool sampleVisible)
    : type_(type),
      alphaU_(std::max(alphaU, kMinAlpha)),
      alphaV_(std::max(alphaV, kMinAlpha)),
      sampleVisible_(sampleVisible && type != MicrofacetType::Phong) {
    scaleAlpha(1.0);
}

void MicrofacetDistribution::scaleAlpha(double s) {
    alphaU_ *= s;
    alphaV_ *= s;
    // Mitsuba's mapping from Beckmann-like roughness to the Phong exponent (Walter et al. 2007 eq. 32).
    exponentU_ = std::max(2.0 / (alphaU_ * alphaU_) - 2.0, 0.0);
    exponentV_ = std::max(2.0 / (alphaV_ * alphaV_) - 2.0, 0.0);
}

double MicrofacetDistribution::phongExponent(const Vec3 &m) const {
    const double sin2 = Frame::sin2Theta(m);
    if (isIsotropic() || sin2 <= 0) return exponentU_;
    return (exponentU_ * m.x * m.x + exponentV_ * m.y * m.y) / sin2;
}

double MicrofacetDistribution::eval(const Vec3 &m) const {
    if (m.z <= 0) return 0.0;
    const double cos2 = m.z * m.z;
    // tan^2(theta_m) (cos^2 phi / alphaU^2 + sin^2 phi / alphaV^2): the stretched squared slope.
    const double e = (m.x * m.x / (alphaU_ * alphaU_) + m.y * m.y / (alphaV_ * alphaV_)) / cos2;
    switch (type_) {
        case MicrofacetType::Beckmann:
            return std::exp(-e) / (kPi * alphaU_ * alphaV_ * cos2 * cos2);
        case MicrofacetType::GGX: {
            const double root = (1.0 + e) * cos2;
            return 1.0 / (kPi * alphaU_ * alphaV_ * root * root);
        }
        case MicrofacetType::Phong:
            // Ashikhmin & Shirley 2000's normalization makes D cos integrate to one for any exponents.
            return std::sqrt((exponentU_ + 2.0) * (exponentV_ + 2.0)) * kInvTwoPi * std::pow(m.z, phongExponent(m));
    }
    return 0.0;
}

double MicrofacetDistribution::projectedAlpha(const Vec3 &v) const {
    const double sin2 = Frame::sin2Theta(v);
    if (isIsotropic() || sin2 <= 0) return alphaU_;
    return std::sqrt((v.x * v.x * alphaU_ * alphaU_ + v.y * v.y * alphaV_ * alphaV_) / sin2);
}

double MicrofacetDistribution::G1(const Vec3 &v, const Vec3 &m) const {
    if (dot(v, m) * v.z <= 0) return 0.0;
    const double tan2 = Frame::sin2Theta(v) / (v.z * v.z);
    if (tan2 == 0) return 1.0;
    switch (type_) {
        case MicrofacetType::GGX:
            return 2.0 / (1.0 + std::sqrt(1.0 + sqr(projectedAlpha(v)) * tan2));
        case MicrofacetType::Beckmann: {
            // Lambda(a) = (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)), a = 1 / (alpha tan theta)
            // (Walter et al. 2007 eq. 27, exact; Mitsuba uses a rational approximation of it).
            const double a = 1.0 / (projectedAlpha(v) * std::sqrt(tan2));
            return 1.0 / (1.0 + 0.5 * (std::exp(-a * a) / (a * kSqrtPi) - std::erfc(a)));
        }
        case MicrofacetType::Phong:
            return 1.0 / (1.0 + phongLambda(phongExponent(v), 1.0 / std::sqrt(tan2)));
    }
    return 0.0;
}

double MicrofacetDistribution::sampleAzimuth(double u, double &invAlphaSqr) const {
    double phi;
    if (isIsotropic()) {
        phi = 2.0 * kPi * u;
    } else {
        // The azimuthal marginal of every anisotropic model here is proportional to
        // 1 / (k^2 cos^2 phi + sin^2 phi); within a quadrant it is inverted by
        // tan(phi) = k tan(pi/2 t). The quadrants are traversed alternately forwards and backwards so
        // that the map stays continuous in u.
        const double k =
            type_ == MicrofacetType::Phong ? std::sqrt((exponentU_ + 2.0) / (exponentV_ + 2.0)) : alphaV_ / alphaU_;
        const int quadrant = std::min(3, static_cast<int>(4.0 * u));
        double t = 4.0 * u - quadrant;
        if (quadrant % 2 == 1) t = 1.0 - t;
        const double phi0 = std::atan(k * std::tan(0.5 * kPi * t));
        const double base[4] = {0.0, kPi, kPi, 2.0 * kPi};
        phi = quadrant % 2 == 0 ? base[quadrant] + phi0 : base[quadrant] - phi0;
    }
    const double c = std::cos(phi), s = std::sin(phi);
    invAlphaSqr = c * c / (alphaU_ * alphaU_) + s * s / (alphaV_ * alphaV_);
    return phi;
}

Vec3 MicrofacetDistribution::sampleAll(const Vec2 &u, double &pdf) const {
    double invAlphaSqr;
    const double phi = sampleAzimuth(u.y, invAlphaSqr);
    double cosTheta;
    switch (type_) {
        case MicrofacetType::Beckmann:
            cosTheta = 1.0 / std::sqrt(1.0 - std::log(1.0 - u.x) / invAlphaSqr);
            break;
        case MicrofacetType::GGX:
            cosTheta = 1.0 / std::sqrt(1.0 + u.x / ((1.0 - u.x) * invAlphaSqr));
            break;
        default: {
            const double c = std::cos(phi), s = std::sin(phi);
            cosTheta = std::pow(u.x, 1.0 / (exponentU_ * c * c + exponentV_ * s * s + 2.0));
        }
    }
    const double sinTheta = safeSqrt(1.0 - cosTheta * cosTheta);
    const Vec3 m(sinTheta * std::cos(phi), sinTheta * std::sin(phi), cosTheta);
    pdf = eval(m) * m.z;
    return m;
}

Vec3 MicrofacetDistribution::sampleVisibleNormal(const Vec3 &wi, const Vec2 &u) const {
    // Both models are handled in the configuration stretched to alpha = 1, where the distribution of
    // visible normals is isotropic about the stretched wi (Heitz 2014 §5.3).
    const Vec3 ws = normalize(Vec3(alphaU_ * wi.x, alphaV_ * wi.y, wi.z));
    if (type_ == MicrofacetType::GGX) {
        // GGX: Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)): the visible
        // normals of the stretched hemisphere are a uniformly sampled disk projected along ws,
        // compressed on the half hidden by the horizon. Exact, unlike the fitted y-slope of 2014.
        const double lensq = ws.x * ws.x + ws.y * ws.y;
        const Vec3 t1 = lensq > 0 ? Vec3(-ws.y, ws.x, 0.0) / std::sqrt(lensq) : Vec3(1, 0, 0);
        const Vec3 t2 = cross(ws, t1);
        const double r = std::sqrt(u.x);
        const SinCos phi = sinCos2Pi(u.y);
        const double p1 = r * phi.cos, s = 0.5 * (1.0 + ws.z);
        const double p2 = (1.0 - s) * safeSqrt(1.0 - p1 * p1) + s * r * phi.sin;
        const Vec3 nh = t1 * p1 + t2 * p2 + ws * safeSqrt(1.0 - p1 * p1 - p2 * p2);
        return normalize(Vec3(alphaU_ * nh.x, alphaV_ * nh.y, std::max(0.0, nh.z)));
    }
    // Beckmann: sample the visible slopes for alpha = 1, rotate them to the azimuth of ws and
    // unstretch (Heitz & d'Eon 2014, Algorithm 1).
    const double sinTheta = Frame::sinTheta(ws);
    const Vec2 slope = sampleBeckmannVisibleSlopes(ws.z, sinTheta, u);
    const double cosPhi = sinTheta > 0 ? ws.x / sinTheta : 1.0, sinPhi = sinTheta > 0 ? ws.y / sinTheta : 0.0;
    const double sx = alphaU_ * (cosPhi * slope.x - sinPhi * slope.y);
    const double sy = alphaV_ * (sinPhi * slope.x + cosPhi * slope.y);
    return normalize(Vec3(-sx, -sy, 1.0));
}

Vec3 MicrofacetDistribution::sample(const Vec3 &wi, const Vec2 &u, double &pdfOut) const {
    if (!sampleVisible_) return sampleAll(u, pdfOut);
    const Vec3 m = sampleVisibleNormal(wi, u);
    pdfOut = pdf(wi, m);
    return m;
}

double MicrofacetDistribution::pdf(const Vec3 &wi, const Vec3 &m) const {
    if (!sampleVisible_) return eval(m) * m.z;
    // D_wi(m) = G1(wi, m) max(0, wi . m) D(m) / cos(theta_i) (Heitz 2014 eq. 38).
    if (wi.z == 0) return 0.0;
    return G1(wi, m) * std::abs(dot(wi, m)) * eval(m) / std::abs(wi.z);
}

bool MicrofacetParams::spatiallyVarying() const { return !alphaU->isConstant() || !alphaV->isConstant(); }

MicrofacetDistribution MicrofacetParams::at(const Intersection &its) const {
    const double au = alphaU->eval(its).average();
    const double av = anisotropic() ? alphaV->eval(its).average() : au;
    return MicrofacetDistribution(type, au, av, sampleVisible);
}

MicrofacetParams readMicrofacetParams(const Properties &props, bool allowAnisotropic) {
    MicrofacetParams p;
    const std::string name = toLower(props.getString("distribution", "beckmann"));
    if (name == "beckmann")
        p.type = MicrofacetType::Beckmann;
    else if (name == "ggx")
        p.type = MicrofacetType::GGX;
    else if (name == "phong" || name == "as")
        p.type = MicrofacetType::Phong;
    else
        props.fail("distribution", "unknown microfacet distribution \"" + name +
                                       "\"; must be \"beckmann\", \"ggx\" or \"phong\" (or \"as\", which "
                                       "Mitsuba 0.6 treats as the anisotropic Phong model)");
    const bool hasU = hasParameter(props, "alphaU"), hasV = hasParameter(props, "alphaV");
    if (hasU || hasV) {
        const std::string given = hasU ? "alphaU" : "alphaV";
        if (!allowAnisotropic) props.fail(given, "this model only supports isotropic roughness ('alpha')");
        if (hasParameter(props, "alpha")) props.fail("alpha", "give either 'alpha' or 'alphaU' and 'alphaV', not both");
        if (!hasU || !hasV) props.fail(given, "'alphaU' and 'alphaV' must be given together");
        p.alphaU = readAlpha(props, "alphaU");
        p.alphaV = readAlpha(props, "alphaV");
    } else {
        p.alphaU = p.alphaV = readAlpha(props, "alpha");
    }
    p.sampleVisible = props.getBool("sampleVisible", true);
    return p;
}

}  // namespace pf
