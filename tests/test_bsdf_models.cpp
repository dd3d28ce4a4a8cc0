// Building blocks of the BSDF plugins: exact Fresnel equations, the named IOR tables, the microfacet
// distributions (normalization, masking, visible-normal densities), the shading-normal correction,
// per-lobe roughness, and the rejection of bad parameters with an error that names the parameter.
#include <algorithm>

#include "bsdf/fresnel.h"
#include "bsdf/ior.h"
#include "bsdf/microfacet.h"
#include "bsdf/quadrature.h"
#include "core/error.h"
#include "test_bsdf_common.h"

namespace pf::test {
namespace {

TEST(Fresnel, DielectricAtNormalIncidence) {
    for (double n : {1.1, 1.333, 1.5, 2.419}) {
        const double expected = sqr((n - 1) / (n + 1));
        double cosT;
        EXPECT_NEAR(fresnelDielectric(1.0, n, cosT), expected, 1e-15) << n;
        EXPECT_DOUBLE_EQ(cosT, -1.0);
        // The same from inside (the boundary is symmetric at normal incidence).
        EXPECT_NEAR(fresnelDielectric(-1.0, n, cosT), expected, 1e-15) << n;
        EXPECT_DOUBLE_EQ(cosT, 1.0);
    }
    EXPECT_EQ(fresnelDielectric(0.3, 1.0), 0.0);  // index-matched: no reflection
}

TEST(Fresnel, TotalInternalReflection) {
    const double n = 1.5, critical = std::asin(1.0 / n);
    double cosT;
    // From inside (cos theta_i < 0), beyond the critical angle everything is reflected.
    for (double theta : {critical + 1e-6, 0.9, 1.2, 1.5}) {
        EXPECT_EQ(fresnelDielectric(-std::cos(theta), n, cosT), 1.0) << theta;
        EXPECT_EQ(cosT, 0.0);
    }
    // Just inside the critical angle some light still leaves, at grazing refraction.
    const double F = fresnelDielectric(-std::cos(critical - 1e-3), n, cosT);
    EXPECT_LT(F, 1.0);
    EXPECT_GT(cosT, 0.0);
    EXPECT_LT(cosT, 0.1);
    // Stokes relations: reflectance is the same for the two directions of a refraction pair.
    for (double theta : {0.1, 0.5, 0.7}) {
        const double Fo = fresnelDielectric(std::cos(theta), n, cosT);
        EXPECT_NEAR(fresnelDielectric(cosT, n), Fo, 1e-14);
    }
}

TEST(Fresnel, ConductorMatchesDielectricWhenKIsZero) {
    for (double n : {1.2, 1.5, 2.4}) {
        for (double c = 0.02; c <= 1.0; c += 0.07) {
            const Spectrum F = fresnelConductor(c, Spectrum(n), Spectrum(0.0));
            EXPECT_NEAR(F.r, fresnelDielectric(c, n), 1e-12) << "eta " << n << " cos " << c;
            EXPECT_EQ(F.r, F.b);
        }
    }
    // eta = 0, k = 1 ("none") is a perfect mirror; absorbing metals reflect less than that.
    for (double c : {0.05, 0.5, 1.0}) {
        EXPECT_NEAR(fresnelConductor(c, Spectrum(0.0), Spectrum(1.0)).g, 1.0, 1e-12);
        const ConductorIOR gold = *lookupConductorIOR("Au");
        const Spectrum F = fresnelConductor(c, gold.eta, gold.k);
        EXPECT_GT(F.min(), 0.0);
        EXPECT_LT(F.max(), 1.0);
        EXPECT_GT(F.r, F.b);  // gold is yellow
    }
}

TEST(Fresnel, DiffuseReflectance) {
    // Reciprocity of the hemispherical averages: 1 - Fdr(1/n) = (1 - Fdr(n)) / n^2, the identity that
    // makes plastic's internal-reflection series conserve energy.
    for (double n : {1.2, 1.49, 2.0}) {
        EXPECT_NEAR(1.0 - fresnelDiffuseReflectance(1.0 / n), (1.0 - fresnelDiffuseReflectance(n)) / (n * n), 1e-10)
            << n;
    }
    // Against an independent midpoint rule in theta with many steps.
    const double n = 1.5;
    double sum = 0;
    const int steps = 200000;
    for (int i = 0; i < steps; ++i) {
        const double theta = (i + 0.5) * (0.5 * kPi / steps);
        sum += fresnelDielectric(std::cos(theta), n) * 2.0 * std::cos(theta) * std::sin(theta);
    }
    EXPECT_NEAR(fresnelDiffuseReflectance(n), sum * 0.5 * kPi / steps, 1e-8);
    EXPECT_NEAR(fresnelDiffuseReflectance(n), 0.0918, 5e-4);  // the textbook value for glass
}

TEST(IOR, NamedTables) {
    EXPECT_DOUBLE_EQ(*lookupDielectricIOR("water"), 1.333);
    EXPECT_DOUBLE_EQ(*lookupDielectricIOR("BK7"), 1.5046);
    EXPECT_DOUBLE_EQ(*lookupDielectricIOR("vacuum"), 1.0);
    EXPECT_DOUBLE_EQ(*lookupDielectricIOR("diamond"), 2.419);
    EXPECT_DOUBLE_EQ(*lookupDielectricIOR("acrylic glass"), 1.49);
    EXPECT_FALSE(lookupDielectricIOR("unobtainium").has_value());
    for (const char *metal : {"Ag", "Al", "Au", "Cu", "Cr", "W", "cu"}) {
        const auto ior = lookupConductorIOR(metal);
        ASSERT_TRUE(ior.has_value()) << metal;
        EXPECT_GT(ior->k.min(), 1.0) << metal;  // metals absorb strongly in the visible range
    }
    const ConductorIOR none = *lookupConductorIOR("none");
    EXPECT_EQ(none.eta, Spectrum(0.0));
    EXPECT_EQ(none.k, Spectrum(1.0));
    EXPECT_FALSE(lookupConductorIOR("adamantium").has_value());
    // Copper's red channel reflects most: Mitsuba's RGB conversion of the measured spectra.
    const ConductorIOR cu = *lookupConductorIOR("Cu");
    const Spectrum F = fresnelConductor(1.0, cu.eta, cu.k);
    EXPECT_GT(F.r, F.g);
    EXPECT_GT(F.g, F.b - 0.05);
}

TEST(IOR, ParametersAreRelativeToTheExterior) {
    const Properties props = makeProperties("conductor", {{"material", "Au"}, {"extEta", "water"}});
    const ConductorIOR ior = readConductorIOR(props);
    const ConductorIOR gold = *lookupConductorIOR("Au");
    EXPECT_NEAR(ior.eta.g, gold.eta.g / 1.333, 1e-12);
    EXPECT_NEAR(ior.k.b, gold.k.b / 1.333, 1e-12);
    const Properties glass = makeProperties("dielectric", {{"intIOR", 1.7}});
    EXPECT_DOUBLE_EQ(readDielectricIOR(glass, "intIOR", "bk7"), 1.7);
    EXPECT_DOUBLE_EQ(readDielectricIOR(glass, "extIOR", "air"), 1.000277);
}

// \int_{hemisphere} f(m) dm over (theta, phi), composite Gauss-Legendre in theta (fine enough for
// alpha = 0.05 lobes) and the periodic trapezoid rule in phi.
template <typename F>
double integrateHemisphere(const F &f) {
    const int nPhi = 256;
    double sum = 0;
    forEachGaussLegendreNode(96, [&](double x, double w) {
        const double theta = 0.5 * kPi * x;
        for (int j = 0; j < nPhi; ++j) {
            const double phi = 2 * kPi * (j + 0.5) / nPhi;
            const Vec3 m(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
            sum += w * f(m) * std::sin(theta);
        }
    });
    return sum * 0.5 * kPi * 2 * kPi / nPhi;
}

TEST(Microfacet, NormalDistributionsAreNormalized) {
    for (MicrofacetType type : {MicrofacetType::Beckmann, MicrofacetType::GGX, MicrofacetType::Phong}) {
        for (const auto &[au, av] : {std::pair{0.05, 0.05}, {0.3, 0.3}, {1.0, 1.0}, {0.1, 0.4}, {0.6, 0.2}}) {
            const MicrofacetDistribution d(type, au, av, true);
            // GGX's long tail converges slowly near the horizon; 1e-4 is far below what matters.
            EXPECT_NEAR(integrateHemisphere([&](const Vec3 &m) { return d.eval(m) * m.z; }), 1.0, 1e-4)
                << static_cast<int>(type) << " " << au << " " << av;
        }
    }
}

TEST(Microfacet, VisibleNormalDensitiesAreNormalized) {
    // Integrating to one requires G1 to be the exact Smith function of D: the check of the masking
    // terms (Heitz 2014 eq. 38). Isotropic Phong's Lambda is integrated numerically, so it is included.
    for (MicrofacetType type : {MicrofacetType::Beckmann, MicrofacetType::GGX, MicrofacetType::Phong}) {
        for (const auto &[au, av] : {std::pair{0.05, 0.05}, {0.3, 0.3}, {0.8, 0.8}, {0.1, 0.4}}) {
            if (type == MicrofacetType::Phong && au != av) continue;
            const MicrofacetDistribution d(type, au, av, true);
            for (double theta : {0.0, 45.0, 80.0, 89.0}) {
                const Vec3 wi = direction(theta, 30);
                // D_wi(m) = G1(wi, m) max(0, wi.m) D(m) / cos(theta_i), whatever the sampler.
                const double mass = integrateHemisphere(
                    [&](const Vec3 &m) { return d.G1(wi, m) * std::max(0.0, dot(wi, m)) * d.eval(m) / wi.z; });
                EXPECT_NEAR(mass, 1.0, 2e-4) << static_cast<int>(type) << " " << au << " " << av << " theta " << theta;
            }
        }
    }
}

TEST(Microfacet, MaskingProperties) {
    const MicrofacetDistribution ggx(MicrofacetType::GGX, 0.3, 0.3, true);
    const MicrofacetDistribution beckmann(MicrofacetType::Beckmann, 0.3, 0.3, true);
    const Vec3 up(0, 0, 1), m = normalize(Vec3(0.1, 0.2, 1.0));
    EXPECT_EQ(ggx.G1(up, m), 1.0);
    EXPECT_EQ(ggx.G1(direction(80, 0), normalize(Vec3(-1.0, 0.0, 0.1))), 0.0);  // back side of the microfacet
    const Vec3 v = direction(70, 0);
    const double t = std::tan(degToRad(70));
    EXPECT_NEAR(ggx.G1(v, up), 2.0 / (1.0 + std::sqrt(1.0 + 0.09 * t * t)), 1e-14);
    // Beckmann: exact Lambda, within Mitsuba's stated 0.35% of its rational approximation.
    const double a = 1.0 / (0.3 * t);
    const double mitsuba = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
    EXPECT_NEAR(beckmann.G1(v, up), mitsuba, 0.0035 * mitsuba);
    // Masking decreases towards grazing.
    EXPECT_GT(beckmann.G1(direction(30, 0), up), beckmann.G1(direction(80, 0), up));
    // Phong has no visible-normal sampler (as in Mitsuba 0.6).
    EXPECT_FALSE(MicrofacetDistribution(MicrofacetType::Phong, 0.3, 0.3, true).sampleVisible());
}

TEST(Microfacet, NormalSamplingChi2) {
    int count = 0;
    const std::vector<std::tuple<MicrofacetType, double, double, bool, double>> cases = {
        {MicrofacetType::Beckmann, 0.3, 0.3, true, 60},  {MicrofacetType::Beckmann, 0.2, 0.5, true, 80},
        {MicrofacetType::GGX, 0.3, 0.3, true, 60},       {MicrofacetType::GGX, 0.5, 0.2, true, 85},
        {MicrofacetType::Beckmann, 0.2, 0.5, false, 30}, {MicrofacetType::GGX, 0.5, 0.2, false, 30},
        {MicrofacetType::Phong, 0.3, 0.3, false, 30},    {MicrofacetType::Phong, 0.2, 0.6, false, 30},
    };
    for (const auto &[type, au, av, visible, theta] : cases) {
        const MicrofacetDistribution d(type, au, av, visible);
        const Vec3 wi = direction(theta, 25);
        const Chi2Result r = chi2Lobe(
            [&](PCG32 &rng, Vec3 &m) {
                double pdf;
                m = d.sample(wi, Vec2(rng.nextDouble(), rng.nextDouble()), pdf);
                return pdf > 0;
            },
            [&](const Vec3 &m) { return d.pdf(wi, m); }, degToRad(25), 0.08, 200000, static_cast<int>(cases.size()),
            100 + count++);
        EXPECT_TRUE(r.passed) << static_cast<int>(type) << " " << au << "/" << av << " visible " << visible << ": "
                              << r.report;
    }
}

TEST(BSDFBase, ShadingNormalCorrection) {
    Intersection its = flatIntersection();
    const Vec3 wi = normalize(Vec3(0.3, 0.1, 0.8)), wo = normalize(Vec3(-0.5, 0.2, 0.6));
    EXPECT_DOUBLE_EQ(shadingNormalCorrection(its, wi, wo), 1.0);  // shading normal = geometric normal
    its.shFrame = Frame(normalize(Vec3(0.2, 0.0, 1.0)));
    const double expected =
        std::abs(dot(wi, its.n) * dot(wo, its.shFrame.n)) / std::abs(dot(wi, its.shFrame.n) * dot(wo, its.n));
    EXPECT_NEAR(shadingNormalCorrection(its, wi, wo), expected, 1e-15);
    // A direction between the two tangent planes would leak light through the surface.
    const Vec3 leak = normalize(Vec3(-1.0, 0.0, 0.1));
    ASSERT_LT(dot(leak, its.shFrame.n) * dot(leak, its.n), 0.0);
    EXPECT_EQ(shadingNormalCorrection(its, leak, wo), 0.0);
    EXPECT_EQ(shadingNormalCorrection(its, wi, leak), 0.0);
}

TEST(BSDFBase, RoughnessPerLobeAndFlags) {
    const Intersection its = flatIntersection();
    const auto diffuse = makeBSDF("diffuse");
    EXPECT_EQ(diffuse->roughness(its, BSDFFlags::DiffuseReflection), kInfinity);
    EXPECT_EQ(diffuse->flags(), static_cast<uint32_t>(BSDFFlags::DiffuseReflection | BSDFFlags::FrontSide));
    EXPECT_EQ(makeBSDF("conductor")->roughness(its, BSDFFlags::DeltaReflection), 0.0);
    const auto rc = makeBSDF("roughconductor", {{"alphaU", 0.1}, {"alphaV", 0.3}});
    EXPECT_DOUBLE_EQ(rc->roughness(its, BSDFFlags::GlossyReflection), 0.2);
    EXPECT_TRUE(rc->flags() & BSDFFlags::Anisotropic);
    const auto rd = makeBSDF("roughdielectric", {{"alpha", 0.25}});
    EXPECT_DOUBLE_EQ(rd->roughness(its, BSDFFlags::GlossyTransmission), 0.25);
    EXPECT_NEAR(rd->eta(), 1.5046 / 1.000277, 1e-12);
    EXPECT_TRUE((rd->flags() & BSDFFlags::FrontSide) && (rd->flags() & BSDFFlags::BackSide));
    const auto rp = makeBSDF("roughplastic", {{"alpha", 0.15}});
    EXPECT_DOUBLE_EQ(rp->roughness(its, BSDFFlags::GlossyReflection), 0.15);
    EXPECT_EQ(rp->roughness(its, BSDFFlags::DiffuseReflection), kInfinity);
    const auto plastic = makeBSDF("plastic");
    EXPECT_EQ(plastic->roughness(its, BSDFFlags::DeltaReflection), 0.0);
    EXPECT_EQ(plastic->roughness(its, BSDFFlags::DiffuseReflection), kInfinity);
    EXPECT_TRUE(makeBSDF("null")->isNull());
    EXPECT_FALSE(makeBSDF("thindielectric")->isNull());
    EXPECT_TRUE(makeBSDF("thindielectric")->flags() & BSDFFlags::Null);
    const auto mask = makeBSDF("mask", {}, {nested(rc)});
    EXPECT_EQ(mask->roughness(its, BSDFFlags::Null), 0.0);
    EXPECT_DOUBLE_EQ(mask->roughness(its, BSDFFlags::GlossyReflection), 0.2);
    const auto twosided = makeBSDF("twosided", {}, {nested(rc)});
    EXPECT_TRUE(twosided->flags() & BSDFFlags::BackSide);
    EXPECT_DOUBLE_EQ(twosided->roughness(its, BSDFFlags::GlossyReflection), 0.2);
    // Every plugin of the table can be built with its defaults where it needs no children.
    for (const std::string &name : pluginNames(ObjectKind::BSDF)) {
        if (name == "twosided" || name == "mask" || name == "bumpmap") continue;
        EXPECT_NO_THROW(makeBSDF(name)) << name;
    }
    EXPECT_EQ(pluginNames(ObjectKind::BSDF).size(), 13u);
}

TEST(BSDFBase, BumpMapTiltsTheShadingNormal) {
    const Intersection its = flatIntersection();
    const double g = 0.5;
    const auto bump = makeBSDF("bumpmap", {},
                               {nested(makeBSDF("diffuse", {{"reflectance", 1.0}})),
                                {"", ObjectKind::Texture, std::make_shared<LinearHeight>(g, 0.0)}});
    // h = g u: the bumped normal is normalize(-g, 0, 1), and diffuse evaluates its cosine.
    const Vec3 nb = normalize(Vec3(-g, 0.0, 1.0));
    const Vec3 wi = direction(20, 180), wo = direction(40, 180);
    const double f = bump->eval(BSDFContext(), its, wi, wo, Measure::SolidAngle).g;
    EXPECT_NEAR(f, kInvPi * dot(wo, nb), 1e-12);
    // A constant height leaves the nested BSDF unchanged.
    const auto flat = makeBSDF(
        "bumpmap", {},
        {nested(makeBSDF("diffuse")), {"", ObjectKind::Texture, std::make_shared<ConstantTexture>(Spectrum(0.3))}});
    EXPECT_NEAR(flat->eval(BSDFContext(), its, wi, wo, Measure::SolidAngle).g, 0.5 * kInvPi * wo.z, 1e-12);
    // Directions on the other side of the bumped surface than of the shading frame get nothing.
    const Vec3 grazing = direction(85, 0);
    ASSERT_LT(dot(grazing, nb), 0.0);
    EXPECT_TRUE(bump->eval(BSDFContext(), its, wi, grazing, Measure::SolidAngle).isBlack());
}

// The SceneError message must name the parameter at fault.
void expectRejected(const std::string &plugin, const std::vector<Param> &params, const std::string &param,
                    const std::vector<Child> &children = {}) {
    try {
        makeBSDF(plugin, params, children);
        ADD_FAILURE() << plugin << ": expected a SceneError about '" << param << "'";
    } catch (const SceneError &e) {
        EXPECT_NE(std::string(e.what()).find(param), std::string::npos)
            << plugin << ": the message does not name '" << param << "': " << e.what();
    }
}

TEST(BSDFParameters, BadValuesAreRejectedByName) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    expectRejected("diffuse", {{"reflectance", 1.5}}, "reflectance");
    expectRejected("diffuse", {{"reflectance", Spectrum(0.5, -0.1, 0.5)}}, "reflectance");
    expectRejected("diffuse", {{"reflectance", nan}}, "reflectance");
    expectRejected("diffuse", {{"diffuseReflectance", 2.0}}, "diffuseReflectance");
    expectRejected("roughconductor", {{"alpha", -0.1}}, "alpha");
    expectRejected("roughconductor", {{"alpha", nan}}, "alpha");
    expectRejected("roughconductor", {{"distribution", "blinn"}}, "distribution");
    expectRejected("roughconductor", {{"alpha", 0.1}, {"alphaU", 0.2}, {"alphaV", 0.2}}, "alpha");
    expectRejected("roughconductor", {{"alphaU", 0.2}}, "alphaU");
    expectRejected("roughconductor", {{"material", "Unobtainium"}}, "material");
    expectRejected("roughconductor", {{"eta", -1.0}}, "eta");
    expectRejected("conductor", {{"k", Spectrum(1, -2, 3)}}, "k");
    expectRejected("conductor", {{"extEta", "vapour"}}, "extEta");
    expectRejected("conductor", {{"specularReflectance", 1.2}}, "specularReflectance");
    expectRejected("dielectric", {{"intIOR", "kryptonite"}}, "intIOR");
    expectRejected("dielectric", {{"intIOR", -1.5}}, "intIOR");
    expectRejected("dielectric", {{"extIOR", 0.0}}, "extIOR");
    expectRejected("dielectric", {{"specularTransmittance", -0.5}}, "specularTransmittance");
    expectRejected("thindielectric", {{"intIOR", nan}}, "intIOR");
    expectRejected("roughdielectric", {{"alphaV", 0.3}}, "alphaV");
    expectRejected("roughdielectric", {{"sampleVisible", "yes"}}, "sampleVisible");
    expectRejected("plastic", {{"diffuseReflectance", 1.01}}, "diffuseReflectance");
    expectRejected("plastic", {{"intIOR", "glass of milk"}}, "intIOR");
    expectRejected("roughplastic", {{"alphaU", 0.1}, {"alphaV", 0.1}}, "alphaU");
    expectRejected("roughplastic", {{"distribution", "cauchy"}}, "distribution");
    expectRejected("ward", {{"variant", "lafortune"}}, "variant");
    expectRejected("ward", {{"alphaU", 0.0}}, "alphaU");
    expectRejected("ward", {{"specularReflectance", 3.0}}, "specularReflectance");
    const auto diffuse = makeBSDF("diffuse");
    expectRejected("mask", {{"opacity", 1.5}}, "opacity", {nested(diffuse)});
    expectRejected("mask", {}, "nested BSDF");
    expectRejected("twosided", {}, "nested BSDF");
    expectRejected("twosided", {}, "nested BSDF", {nested(diffuse), nested(diffuse), nested(diffuse)});
    expectRejected("twosided", {}, "transmission", {nested(makeBSDF("dielectric"))});
    expectRejected("bumpmap", {}, "texture", {nested(diffuse)});
    // A misspelt parameter is left unused, which the loader reports by name.
    EXPECT_THROW(makeBSDF("diffuse", {{"reflectanse", 0.3}}), SceneError);
    // Mitsuba 0.6 reads "as" as the anisotropic Phong model.
    EXPECT_NO_THROW(makeBSDF("roughconductor", {{"distribution", "as"}, {"alphaU", 0.1}, {"alphaV", 0.2}}));
}

}  // namespace
}  // namespace pf::test
