// The path tracer against scenes with closed-form answers, Mitsuba's depth semantics, and
// determinism across thread counts. Every comparison is a confidence interval at a fixed seed: the
// tolerance is 4 standard errors of the estimate, and the standard error itself must be small enough
// for the check to mean something.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "support/render_util.h"

namespace pf::test {
namespace {

std::string camera(const std::string &origin, const std::string &target, double fov, int res,
                   const std::string &up = "0, 1, 0") {
    return R"(<sensor type="perspective"><float name="fov" value=")" + std::to_string(fov) +
           R"("/><transform name="toWorld"><lookat origin=")" + origin + R"(" target=")" + target + R"(" up=")" + up +
           R"("/></transform><film type="hdrfilm"><integer name="width" value=")" + std::to_string(res) +
           R"("/><integer name="height" value=")" + std::to_string(res) +
           R"("/><rfilter type="box"/></film></sensor>)";
}

// Camera at the centre of a sphere that emits Le inwards and reflects diffusely with albedo rho: every
// point sees L = Le (1 + rho + ... + rho^(maxDepth-1)), or Le / (1 - rho) when unbounded.
std::string emittingSphereScene(double Le, double rho, int maxDepth) {
    return R"(<scene version="0.6.0"><integrator type="path"><integer name="maxDepth" value=")" +
           std::to_string(maxDepth) + R"("/></integrator>)" + camera("0, 0, 0", "0, 0, 1", 60, 32) +
           R"(<shape type="sphere"><float name="radius" value="10"/><boolean name="flipNormals" value="true"/>
              <bsdf type="diffuse"><spectrum name="reflectance" value=")" +
           std::to_string(rho) + R"("/></bsdf><emitter type="area"><spectrum name="radiance" value=")" +
           std::to_string(Le) + R"("/></emitter></shape></scene>)";
}

void expectMean(const Bitmap &img, double expected, double maxRelStderr, const char *what) {
    const MeanCI m = regionMean(img, 0, 0, img.width, img.height);
    EXPECT_LT(m.stderr_, maxRelStderr * expected) << what << ": estimate too noisy for a meaningful check";
    EXPECT_NEAR(m.mean, expected, 4 * m.stderr_ + 1e-12) << what << " (stderr " << m.stderr_ << ")";
}

TEST(PathTracer, SphereInsideUniformlyEmittingSphere) {
    const double Le = 1.0, rho = 0.5;
    const RenderOutput out = renderXml(emittingSphereScene(Le, rho, -1), "path", 16);
    expectMean(out.image, Le / (1 - rho), 0.01, "unbounded depth");
}

TEST(PathTracer, MaxDepthCountsEdgesLikeMitsuba) {
    const double Le = 1.0, rho = 0.5;
    double expected = 0, term = Le;
    for (int depth = 1; depth <= 4; ++depth) {
        expected += term;
        term *= rho;
        const RenderOutput out = renderXml(emittingSphereScene(Le, rho, depth), "path", 8);
        expectMean(out.image, expected, 0.01, ("maxDepth " + std::to_string(depth)).c_str());
        if (depth == 1) {
            // Only directly visible emitters: no noise at all.
            const MeanCI m = regionMean(out.image, 0, 0, out.image.width, out.image.height);
            EXPECT_NEAR(m.stderr_, 0.0, 1e-6);
        }
    }
}

// White furnace: a convex diffuse object under a uniform environment only ever sees the environment,
// so it reflects exactly rho * L everywhere, whatever the mix of NEE and BSDF sampling.
TEST(PathTracer, FurnaceConvexDiffuseSphere) {
    const double rho = 0.6, Lenv = 1.5;
    const std::string xml = R"(<scene version="0.6.0"><integrator type="path"/>)" +
                            camera("0, 0, -3", "0, 0, 0", 10, 24) +
                            R"(<emitter type="constant"><spectrum name="radiance" value=")" + std::to_string(Lenv) +
                            R"("/></emitter><shape type="sphere"><float name="radius" value="1"/>
                            <bsdf type="diffuse"><spectrum name="reflectance" value=")" +
                            std::to_string(rho) + R"("/></bsdf></shape></scene>)";
    const RenderOutput out = renderXml(xml, "path", 16);
    expectMean(out.image, rho * Lenv, 0.01, "furnace sphere");
}

// A large diffuse plane under a uniform environment: rho * L (the plane sees the upper hemisphere).
TEST(PathTracer, DiffusePlaneUnderConstantEmitter) {
    const double rho = 0.3, Lenv = 2.0;
    const std::string xml = R"(<scene version="0.6.0"><integrator type="path"/>)" +
                            camera("0, 1, 0", "0, 0, 0", 20, 24, "0, 0, 1") +
                            R"(<emitter type="constant"><spectrum name="radiance" value=")" + std::to_string(Lenv) +
                            R"("/></emitter><shape type="rectangle"><transform name="toWorld">
                            <scale value="1000"/><rotate x="1" angle="-90"/></transform>
                            <bsdf type="diffuse"><spectrum name="reflectance" value=")" +
                            std::to_string(rho) + R"("/></bsdf></shape></scene>)";
    const RenderOutput out = renderXml(xml, "path", 16);
    expectMean(out.image, rho * Lenv, 0.01, "diffuse plane");
}

// Same seed, same bits, whatever the thread count (tiles are merged in a fixed order).
TEST(PathTracer, SameBitsWithOneAndTwoThreads) {
    const std::string xml = emittingSphereScene(1.0, 0.7, -1);
    const RenderOutput a = renderXml(xml, "path", 4, 7, 1);
    const RenderOutput b = renderXml(xml, "path", 4, 7, 2);
    ASSERT_EQ(a.image.rgb.size(), b.image.rgb.size());
    EXPECT_EQ(0, std::memcmp(a.image.rgb.data(), b.image.rgb.data(), a.image.rgb.size() * sizeof(float)));
    const RenderOutput c = renderXml(xml, "path", 4, 8, 2);
    EXPECT_NE(0, std::memcmp(a.image.rgb.data(), c.image.rgb.data(), a.image.rgb.size() * sizeof(float)))
        << "a different seed must give a different image";
}

TEST(PathTracer, RejectsBadParameters) {
    std::string xml = emittingSphereScene(1.0, 0.5, 0);
    EXPECT_THROW(renderXml(xml, "path", 1), SceneError);
    xml = emittingSphereScene(1.0, 0.5, -1);
    const std::string marker = R"(<integer name="maxDepth" value="-1"/>)";
    xml.replace(xml.find(marker), marker.size(), R"(<integer name="maxDepht" value="3"/>)");
    EXPECT_THROW(renderXml(xml, "path", 1), SceneError) << "misspelt integrator parameter must be rejected";
}

}  // namespace
}  // namespace pf::test
