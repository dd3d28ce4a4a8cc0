// Shared helpers of the BSDF test executables (test_bsdf_*.cpp): building plugins from parameters as
// the scene loader would, a flat local shading frame, and sampling/evaluation wrappers.
#pragma once
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bsdf/bsdf.h"
#include "core/frame.h"
#include "scene/plugins.h"
#include "scene/properties.h"
#include "support/chi2.h"
#include "texture/texture.h"

namespace pf::test {

// One parameter of a plugin: a float, a string, a boolean or an RGB spectrum.
struct Param {
    std::string name;
    Properties::Type type;
    Properties::Value value;
    Param(std::string n, double v) : name(std::move(n)), type(Properties::Type::Float), value(v) {}
    Param(std::string n, const char *v) : name(std::move(n)), type(Properties::Type::String), value(std::string(v)) {}
    Param(std::string n, bool v) : name(std::move(n)), type(Properties::Type::Boolean), value(v) {}
    Param(std::string n, const Spectrum &v) : name(std::move(n)), type(Properties::Type::Spectrum), value(v) {}
};

// A nested object (BSDF or texture) handed to a plugin as a child.
struct Child {
    std::string name;
    ObjectKind kind;
    std::shared_ptr<Object> object;
};

inline Properties makeProperties(const std::string &plugin, const std::vector<Param> &params,
                                 const std::vector<Child> &children = {}) {
    const SourceLocation loc{"test.xml", 1};
    Properties props(ObjectKind::BSDF, plugin, loc);
    for (const Param &p : params) props.set(p.name, p.type, p.value, loc);
    for (const Child &c : children) props.addChild({c.name, c.kind, c.object, loc, false});
    return props;
}

// Builds a BSDF through the plugin table, as the loader does, and checks that every parameter was
// consumed (a misspelt test parameter would otherwise silently test the default).
inline std::shared_ptr<BSDF> makeBSDF(const std::string &plugin, const std::vector<Param> &params = {},
                                      const std::vector<Child> &children = {}) {
    const PluginFactory *factory = findPlugin(ObjectKind::BSDF, plugin);
    if (!factory) throw std::runtime_error("no BSDF plugin " + plugin);
    const Properties props = makeProperties(plugin, params, children);
    std::shared_ptr<Object> obj = (*factory)(props, LoadContext{});
    props.checkAllUsed();
    return std::static_pointer_cast<BSDF>(obj);
}

inline Child nested(std::shared_ptr<BSDF> bsdf, const std::string &name = "") {
    return {name, ObjectKind::BSDF, std::move(bsdf)};
}

// A flat surface point whose shading frame is the identity: local and world directions coincide.
inline Intersection flatIntersection() {
    Intersection its;
    its.p = Vec3(0, 0, 0);
    its.n = Vec3(0, 0, 1);
    its.shFrame = Frame();
    its.dpdu = Vec3(1, 0, 0);
    its.dpdv = Vec3(0, 1, 0);
    its.uv = Vec2(0.5, 0.5);
    return its;
}

// Unit direction from polar angle theta and azimuth phi in degrees (theta > 90 lies below).
inline Vec3 direction(double thetaDeg, double phiDeg) {
    const double t = degToRad(thetaDeg), p = degToRad(phiDeg);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

// Uniformly random unit vector.
inline Vec3 randomDirection(PCG32 &rng) {
    const double z = 2.0 * rng.nextDouble() - 1.0, phi = 2.0 * kPi * rng.nextDouble();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
}

inline double relDiff(double a, double b) { return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-300}); }

inline const char *modeName(TransportMode m) { return m == TransportMode::Radiance ? "radiance" : "importance"; }

// Result of sampling one direction.
struct Sampled {
    Spectrum weight;
    BSDFSample bs;
};

inline Sampled sampleOnce(const BSDF &bsdf, const BSDFContext &ctx, const Intersection &its, const Vec3 &wi,
                          PCG32 &rng) {
    Sampled s;
    const double u1 = rng.nextDouble();
    const Vec2 u2(rng.nextDouble(), rng.nextDouble());
    s.weight = bsdf.sample(ctx, its, wi, s.bs, u1, u2);
    return s;
}

// A height map for bumpmap tests: h(u, v) = gu u + gv v, with its exact gradient.
class LinearHeight final : public Texture {
public:
    LinearHeight(double gu, double gv) : gu_(gu), gv_(gv) {}
    Spectrum eval(const Intersection &its) const override { return Spectrum(gu_ * its.uv.x + gv_ * its.uv.y); }
    Spectrum average() const override { return Spectrum(0.5 * (gu_ + gv_)); }
    Spectrum maximum() const override { return Spectrum(std::max(0.0, gu_) + std::max(0.0, gv_)); }
    void evalGradient(const Intersection &, Spectrum &dfdu, Spectrum &dfdv) const override {
        dfdu = Spectrum(gu_);
        dfdv = Spectrum(gv_);
    }

private:
    double gu_, gv_;
};

// Chi-square test of a direction sampler against its density, for lobes that lie along the plane
// through the z axis at azimuth phiPlane (reflected and refracted lobes lie in the plane of
// incidence, microfacet normals around z). The histogram is taken in a frame whose equator is that
// plane: there the (cos theta, phi) bins are close to square in angle, so that narrow lobes are
// resolved by bins of `binAngle` radians instead of collapsing into a polar cap. The horizon z = 0
// becomes the meridians phi = 0 and phi = pi of that frame, which are kept on bin edges; the expected
// counts are integrated with a Gauss-Legendre rule, whose nodes lie strictly inside the bins, so that
// the jump of a glossy pdf at the horizon costs no accuracy (a rule with nodes on the bin edges, like
// the shared chi2Sphere's Simpson rule, samples the pdf exactly on the jump).
inline Chi2Result chi2Lobe(const DirectionSampler &sample, const DirectionPdf &pdf, double phiPlane, double binAngle,
                           int sampleCount, int testCount, uint64_t seed) {
    const double cp = std::cos(phiPlane), sp = std::sin(phiPlane);
    // Rotate the plane's azimuth to zero, then turn the xz plane into the equator (rotation about x).
    const auto toHist = [=](const Vec3 &v) {
        const Vec3 a(cp * v.x + sp * v.y, -sp * v.x + cp * v.y, v.z);
        return Vec3(a.x, -a.z, a.y);
    };
    const auto fromHist = [=](const Vec3 &h) {
        const Vec3 a(h.x, h.z, -h.y);
        return Vec3(cp * a.x - sp * a.y, sp * a.x + cp * a.y, a.z);
    };
    const int nT = std::max(10, 2 * static_cast<int>(std::lround(1.0 / binAngle)));
    const int nP = std::max(20, 2 * static_cast<int>(std::lround(kPi / binAngle)));
    std::vector<double> observed(static_cast<size_t>(nT) * nP, 0.0), expected(observed.size(), 0.0);
    PCG32 rng(seed, 0x5bd1e995ULL);
    for (int i = 0; i < sampleCount; ++i) {
        Vec3 d;
        if (!sample(rng, d)) continue;
        const Vec3 h = toHist(d);
        double phi = std::atan2(h.y, h.x);
        if (phi < 0) phi += 2 * kPi;
        const int t = std::min(nT - 1, static_cast<int>((clamp(h.z, -1.0, 1.0) + 1.0) * 0.5 * nT));
        const int p = std::min(nP - 1, static_cast<int>(phi / (2 * kPi) * nP));
        observed[static_cast<size_t>(t) * nP + p] += 1.0;
    }
    // 4-point Gauss-Legendre per bin and dimension, in (cos theta, phi) where d omega = dz dphi. A bin
    // in which some points see density and others none contains an edge of the pdf's support (e.g.
    // where the generalized half vector of a rough dielectric crosses the horizon); it is split into
    // quarters, recursively, so that the jump costs no more than a sliver of a bin.
    const auto pdfAt = [&](double z, double phi) {
        const double r = std::sqrt(std::max(0.0, 1 - z * z));
        return pdf(fromHist(Vec3(r * std::cos(phi), r * std::sin(phi), z)));
    };
    const std::function<double(double, double, double, double, int)> integrate = [&](double z0, double z1, double p0,
                                                                                     double p1, int depth) -> double {
        constexpr double x4[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
        constexpr double w4[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
        double acc = 0;
        int zeros = 0;
        for (int i = 0; i < 4; ++i) {
            for (int j = 0; j < 4; ++j) {
                const double v = pdfAt(z0 + (z1 - z0) * 0.5 * (1 + x4[i]), p0 + (p1 - p0) * 0.5 * (1 + x4[j]));
                zeros += v == 0;
                acc += w4[i] * w4[j] * v;
            }
        }
        // The corners and edge midpoints only detect a support edge that slips between the nodes.
        int detectZeros = 0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) detectZeros += pdfAt(z0 + (z1 - z0) * 0.5 * i, p0 + (p1 - p0) * 0.5 * j) == 0;
        const bool mixed =
            (zeros > 0 && zeros < 16) || (zeros == 16 && detectZeros < 9) || (zeros == 0 && detectZeros > 0);
        if (mixed && depth < 4) {
            const double zm = 0.5 * (z0 + z1), pm = 0.5 * (p0 + p1);
            return integrate(z0, zm, p0, pm, depth + 1) + integrate(zm, z1, p0, pm, depth + 1) +
                   integrate(z0, zm, pm, p1, depth + 1) + integrate(zm, z1, pm, p1, depth + 1);
        }
        return acc * 0.25 * (z1 - z0) * (p1 - p0);
    };
    const double dz = 2.0 / nT, dphi = 2 * kPi / nP;
    for (int t = 0; t < nT; ++t)
        for (int p = 0; p < nP; ++p)
            expected[static_cast<size_t>(t) * nP + p] =
                integrate(-1.0 + t * dz, -1.0 + (t + 1) * dz, p * dphi, (p + 1) * dphi, 0) * sampleCount;
    return chi2Histogram(observed, expected, 0.01, testCount);
}

// The chi-square test of bsdf.sample() against bsdf.pdf() for the smooth lobes at incident direction wi.
struct Chi2Case {
    std::string label;
    std::shared_ptr<BSDF> bsdf;
    Vec3 wi;
    TransportMode mode = TransportMode::Radiance;
    double binAngle = 0.15;  // angular bin size (radians); about a third of the narrowest lobe's width
};

inline Chi2Result runChi2(const Chi2Case &c, int testCount, uint64_t seed, int sampleCount) {
    const Intersection its = flatIntersection();
    const BSDFContext ctx(c.mode);
    const double phiI = (c.wi.x == 0 && c.wi.y == 0) ? 0.0 : std::atan2(c.wi.y, c.wi.x);
    return chi2Lobe(
        [&](PCG32 &rng, Vec3 &dir) {
            const Sampled s = sampleOnce(*c.bsdf, ctx, its, c.wi, rng);
            if (s.weight.isBlack() || !(s.bs.pdf > 0) || !(s.bs.sampledType & BSDFFlags::Smooth)) return false;
            dir = s.bs.wo;
            return true;
        },
        [&](const Vec3 &d) { return c.bsdf->pdf(ctx, its, c.wi, d, Measure::SolidAngle); }, phiI, c.binAngle,
        sampleCount, testCount, seed);
}

// Runs every case with the Sidak correction for their number and reports each failure by name.
inline void expectChi2(const std::vector<Chi2Case> &cases, int sampleCount) {
    const int n = static_cast<int>(cases.size());
    for (int i = 0; i < n; ++i) {
        const Chi2Result r = runChi2(cases[i], n, 1000 + i, sampleCount);
        EXPECT_TRUE(r.passed) << cases[i].label << " (" << modeName(cases[i].mode) << "): " << r.report;
    }
}

// Bin size for a lobe of roughness alpha (the reflected lobe is about 1.5 alpha wide).
inline double binAngleFor(double alpha) { return clamp(0.4 * alpha, 0.02, 0.15); }

}  // namespace pf::test
