// Path depth at index-matched boundaries, as Mitsuba 0.6 counts it (README "Path depth"): every crossing
// of a Null lobe is one segment of the path, so a path contributes iff its edges plus its crossings are
// at most maxDepth, in path, volpath, bdpt and the Markov-chain integrators alike.
//
// The scene: a camera far above a slab of homogeneous medium (sigma_t = 1) behind an index-matched top
// face at z = 0, a black Lambertian emitter of radiance Le facing up inside the medium at depth L, the
// slab 100 wide (its sides lie some 50 free paths away, which is e^-50 of nothing). The field of view is
// 0.1 degrees, so every camera ray is vertical to 1e-7 in its cosine. Along such a ray, by depth:
//   1: camera -> top face: nothing (the emitter is one crossing further).
//   2: camera -> top face -> emitter, unscattered:                  T  = Le exp(-sigma_t L).
//   3: camera -> top face -> scattering point -> emitter:           SS = Le sigma_s / 2 Int_0^L
//      exp(-sigma_t z) E_2(sigma_t (L - z)) dz, the isotropic phase function 1 / (4 pi) integrated over the
//      downward hemisphere, E_2(x) = Int_0^1 exp(-x / mu) dmu (upward light would need a second crossing
//      and finds no emitter there).
// So volpath, bdpt and pssmlt must give 0, T, T + SS at maxDepth 1, 2, 3, and `path`, which renders no
// media (Mitsuba's path tracer does not), 0, Le, Le. Under the old rule (crossings free) maxDepth 1 gave T.
// Every integrator is rendered with independent seeds; the whole-image means of the seeds give a mean
// and a standard error (the Markov-chain images are correlated within a render, not across seeds).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "support/render_util.h"

namespace pf::test {
namespace {

constexpr double kSigmaS = 0.6, kSigmaA = 0.4, kSigmaT = kSigmaS + kSigmaA, kL = 1.0, kLe = 1.0;

std::string slabScene(int maxDepth) {
    const std::string L = std::to_string(kL), half = std::to_string((kL + 0.5) / 2);
    return R"(<scene version="0.6.0">
        <integrator type="volpath"><integer name="maxDepth" value=")" +
           std::to_string(maxDepth) + R"("/></integrator>
        <sensor type="perspective"><float name="fov" value="0.1"/>
          <transform name="toWorld"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform>
          <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
            <rfilter type="box"/></film></sensor>
        <medium type="homogeneous" id="fog"><spectrum name="sigmaS" value=")" +
           std::to_string(kSigmaS) + R"("/><spectrum name="sigmaA" value=")" + std::to_string(kSigmaA) + R"("/></medium>
        <shape type="cube"><transform name="toWorld"><scale x="50" y="50" z=")" +
           half + R"("/><translate z="-)" + half + R"("/></transform><ref name="interior" id="fog"/></shape>
        <shape type="rectangle"><transform name="toWorld"><scale value="50"/><translate z="-)" +
           L + R"("/></transform>
          <ref name="interior" id="fog"/><ref name="exterior" id="fog"/>
          <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
          <emitter type="area"><spectrum name="radiance" value=")" +
           std::to_string(kLe) + R"("/></emitter></shape>
        </scene>)";
}

double simpson(const std::function<double(double)> &f, double a, double b, int n) {
    const double h = (b - a) / n;
    double sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
    return sum * h / 3.0;
}

double expIntegral2(double x) {
    // The integrand tends to 0 at mu = 0 for x > 0 (to 1 for x = 0).
    return simpson([x](double mu) { return mu > 0 ? std::exp(-x / mu) : (x > 0 ? 0.0 : 1.0); }, 0.0, 1.0, 4000);
}

double unscattered() { return kLe * std::exp(-kSigmaT * kL); }

double singleScattered() {
    return kLe * kSigmaS / 2 *
           simpson([](double z) { return std::exp(-kSigmaT * z) * expIntegral2(kSigmaT * (kL - z)); }, 0.0, kL, 2000);
}

double expected(const std::string &integrator, int maxDepth) {
    if (maxDepth < 2) return 0.0;
    if (integrator == "path") return kLe;
    return unscattered() + (maxDepth >= 3 ? singleScattered() : 0.0);
}

struct Estimate {
    double mean = 0, stderr_ = 0;
};

Estimate render(const std::string &integrator, int maxDepth, int64_t spp, int seeds) {
    std::string xml = slabScene(maxDepth);
    // The chain integrator renders depths 1 and 2 as its direct component (directSamples volpath samples per
    // pixel) and the rest with chains, whose image mean is the seeding estimate (luminanceSamples, Mitsuba's
    // default of 100000).
    if (integrator == "pssmlt")
        xml.insert(xml.find("</integrator>"), R"(<integer name="luminanceSamples" value="100000"/>
            <integer name="directSamples" value="128"/>)");
    double sum = 0, sum2 = 0;
    for (int s = 0; s < seeds; ++s) {
        const RenderOutput out = renderXml(xml, integrator, spp, 100 + static_cast<uint64_t>(s), 2);
        const double v = regionMean(out.image, 0, 0, out.image.width, out.image.height, 0).mean;
        sum += v;
        sum2 += v * v;
    }
    Estimate e;
    e.mean = sum / seeds;
    e.stderr_ = std::sqrt(std::max(0.0, sum2 / seeds - e.mean * e.mean) / (seeds - 1));
    return e;
}

TEST(IndexMatchedDepth, ClosedFormIsWhatTheTestAssumes) {
    // E_2(0) = 1 and E_2(1) = 0.148495506775922 (Abramowitz & Stegun, table 5.1).
    EXPECT_NEAR(expIntegral2(0.0), 1.0, 1e-9);
    EXPECT_NEAR(expIntegral2(1.0), 0.148495506775922, 1e-6);
    std::printf("slab: T = %.6f, SS = %.6f\n", unscattered(), singleScattered());
}

TEST(IndexMatchedDepth, IntegratorsAgreeWithTheClosedFormAtMaxDepth123) {
    struct Run {
        const char *integrator;
        int64_t spp;
    };
    const std::vector<Run> runs = {{"path", 4}, {"volpath", 32}, {"bdpt", 64}, {"pssmlt", 64}};
    constexpr int kSeeds = 8;
    for (int depth = 1; depth <= 3; ++depth) {
        std::vector<Estimate> media;  // the integrators that render the medium
        for (const Run &r : runs) {
            const Estimate e = render(r.integrator, depth, r.spp, kSeeds);
            const double ref = expected(r.integrator, depth);
            std::printf("maxDepth %d %-8s %.6f +- %.6f (closed form %.6f)\n", depth, r.integrator, e.mean, e.stderr_,
                        ref);
            if (ref == 0) {
                EXPECT_EQ(e.mean, 0.0) << r.integrator << ", maxDepth " << depth;
            } else {
                EXPECT_LT(e.stderr_, 0.01 * ref) << r.integrator << ", maxDepth " << depth << ": too noisy";
                EXPECT_NEAR(e.mean, ref, 4 * e.stderr_ + 1e-6 * ref) << r.integrator << ", maxDepth " << depth;
            }
            if (std::string(r.integrator) != "path") media.push_back(e);
        }
        // And with each other: two-sample intervals of 4 combined standard errors.
        for (size_t i = 0; i < media.size(); ++i)
            for (size_t j = i + 1; j < media.size(); ++j)
                EXPECT_NEAR(media[i].mean, media[j].mean, 4 * std::hypot(media[i].stderr_, media[j].stderr_) + 1e-9)
                    << runs[i + 1].integrator << " vs " << runs[j + 1].integrator << ", maxDepth " << depth;
    }
}

}  // namespace
}  // namespace pf::test
