// The path-space layer ([TH A4]; ALGORITHMS.md §1.1, §1.4, §9.1): EVALPDF against SAMPLENEXT for every
// vertex type and both walks (chi-square), the adjoint EVAL under shading normals, and, on random paths
// of every shared scene, the MIS bookkeeping: BDPT's stored densities equal EVALPDF on the whole path,
// the running-ratio weights of all strategies sum to one and equal the explicit products, and f / p_s
// equals the contribution BDPT computed.
#include <gtest/gtest.h>

#include <cmath>

#include "core/warp.h"
#include "integrators/bdpt.h"
#include "path/mis.h"
#include "path/mutation.h"
#include "scene/medium.h"
#include "scene/shape.h"
#include "support/chi2.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

// A Sampler drawing from the chi-square harness's generator.
class RngSampler final : public Sampler {
public:
    explicit RngSampler(PCG32 &rng) : rng_(rng) {}
    double next1D() override { return rng_.nextDouble(); }

private:
    PCG32 &rng_;
};

const TransportMode kModes[] = {TransportMode::Radiance, TransportMode::Importance};
const char *modeName(TransportMode m) { return m == TransportMode::Radiance ? "radiance" : "importance"; }

std::unique_ptr<Scene> sceneFromXml(const std::string &name, const std::string &body) {
    const std::string xml = R"(<scene version="0.6.0">
        <sensor type="perspective"><float name="fov" value="60"/>
            <transform name="toWorld"><lookat origin="0, 0, 0" target="1, 0, 0" up="0, 0, 1"/></transform>
            <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
        <shape type="sphere"><float name="radius" value="10"/><bsdf type="diffuse"/></shape>)" +
                            body + "</scene>";
    return loadScene(writeFile(tempDir("path-space-" + name), "scene.xml", xml));
}

// A vertex standing for a point with no properties: the predecessor that fixes an incident direction.
PathVertex pointVertex(const Vec3 &p) {
    PathVertex v;
    v.type = VertexType::Medium;
    v.its.p = p;
    v.throughput = Spectrum(1.0);
    return v;
}

// Solid-angle density at `from` of the successor that SAMPLENEXT produced, from EVALPDF (area or volume
// density) converted back: times d^2 over the cosine at the successor.
double solidAngleDensity(const PathVertex &from, const PathVertex &succ, double areaDensity) {
    const Vec3 d = succ.position() - from.position();
    return areaDensity * d.lengthSquared() / succ.cosine(normalize(d));
}

// Chi-square of the directions SAMPLENEXT takes from `cur` (given `pred`) against EVALPDF, for successors
// found by PERTURB along each direction (the enclosing sphere of sceneFromXml catches all of them).
void expectSampleNextMatchesEvalPdf(const Scene &scene, const PathVertex &cur, const PathVertex *pred,
                                    TransportMode mode, const std::string &what, int testCount) {
    Chi2Options opt;
    opt.sampleCount = 100000;
    opt.testCount = testCount;
    // Cones of spot lights and cameras cut cells: integrate finely enough for the discontinuity.
    opt.integrationRes = 30;
    const auto sample = [&](PCG32 &rng, Vec3 &dir) {
        RngSampler sampler(rng);
        PathVertex v = cur, succ;
        PathEdge edge;
        if (!v.sampleNext(scene, sampler, mode, pred, edge, succ) || v.delta) return false;
        dir = normalize(succ.position() - v.position());
        return true;
    };
    PCG32 unusedRng;
    RngSampler unused(unusedRng);
    const auto pdf = [&](const Vec3 &dir) {
        PathVertex succ;
        PathEdge edge;
        if (!cur.perturb(scene, unused, mode, dir, edge, succ)) return 0.0;
        return solidAngleDensity(cur, succ, cur.evalPdf(scene, pred, succ, edge, mode));
    };
    const Chi2Result r = chi2Sphere(sample, pdf, opt);
    EXPECT_TRUE(r.passed) << what << ": " << r.report;
}

// A surface vertex reached by a ray from `origin` towards the origin.
PathVertex surfaceVertex(const Scene &scene, const Vec3 &origin, TransportMode mode) {
    PathVertex v;
    EXPECT_TRUE(scene.intersect(Ray(origin, normalize(-origin)), v.its));
    v.walkMode = mode;
    v.throughput = Spectrum(1.0);
    return v;
}

TEST(PathSpace, SurfaceSampleNextMatchesEvalPdf) {
    const std::vector<std::pair<std::string, std::string>> bsdfs = {
        {"diffuse", R"(<bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf>)"},
        {"roughconductor", R"(<bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>)"},
        {"roughdielectric", R"(<bsdf type="roughdielectric"><float name="alpha" value="0.4"/></bsdf>)"},
        {"plastic", R"(<bsdf type="plastic"/>)"},
    };
    const Vec3 origin = Vec3(std::sin(0.9), 0.0, std::cos(0.9)) * 2.0;
    for (const auto &[name, bsdf] : bsdfs) {
        auto scene = sceneFromXml(
            "surface-" + name, R"(<shape type="rectangle"><transform name="toWorld"><scale value="0.1"/></transform>)" +
                                   bsdf + "</shape>");
        const PathVertex pred = pointVertex(origin);
        for (const TransportMode mode : kModes)
            expectSampleNextMatchesEvalPdf(*scene, surfaceVertex(*scene, origin, mode), &pred, mode,
                                           name + ", " + modeName(mode), 8);
    }
}

// Emitter nodes (the emitter walk) and sensor nodes (the sensor walk, a uniform raster position being the
// direction sample).
TEST(PathSpace, EndpointSampleNextMatchesEvalPdf) {
    const std::vector<std::pair<std::string, std::string>> emitters = {
        {"area", R"(<shape type="rectangle"><transform name="toWorld"><scale value="0.2"/><rotate x="1" angle="30"/>
                    </transform><emitter type="area"><spectrum name="radiance" value="1"/></emitter></shape>)"},
        {"point", R"(<emitter type="point"><point name="position" x="0.1" y="0.2" z="0.3"/></emitter>)"},
        {"spot", R"(<emitter type="spot"><float name="cutoffAngle" value="40"/>
                    <transform name="toWorld"><lookat origin="0, 0, 0" target="1, 1, 0"/></transform></emitter>)"},
    };
    for (const auto &[name, emitter] : emitters) {
        auto scene = sceneFromXml("emitter-" + name, emitter);
        PCG32 rng(3, 5);
        RngSampler sampler(rng);
        PathVertex supernode = PathVertex::emitterSupernode(), node;
        PathEdge edge;
        ASSERT_TRUE(supernode.sampleNext(*scene, sampler, TransportMode::Importance, nullptr, edge, node)) << name;
        expectSampleNextMatchesEvalPdf(*scene, node, &PathVertex::emitterSupernode(), TransportMode::Importance,
                                       name + " emitter", 4);
    }
    // The sensor node's direction sample is its raster position: draw it uniformly over the film.
    auto scene = sceneFromXml("sensor", "");
    PCG32 rng(3, 5);
    RngSampler sampler(rng);
    PathVertex supernode = PathVertex::sensorSupernode(), node;
    PathEdge edge;
    ASSERT_TRUE(supernode.sampleNext(*scene, sampler, TransportMode::Radiance, nullptr, edge, node));
    const Film &film = scene->sensor().film();
    Chi2Options opt;
    opt.sampleCount = 100000;
    opt.testCount = 4;
    opt.integrationRes = 30;
    const auto sample = [&](PCG32 &r, Vec3 &dir) {
        RngSampler s(r);
        PathVertex v = node, succ;
        v.ps.uv = Vec2(s.next1D() * film.cropWidth(), s.next1D() * film.cropHeight());
        PathEdge e;
        if (!v.sampleNext(*scene, s, TransportMode::Radiance, &PathVertex::sensorSupernode(), e, succ)) return false;
        dir = normalize(succ.position() - v.position());
        return true;
    };
    const auto pdf = [&](const Vec3 &dir) {
        PathVertex succ;
        PathEdge e;
        if (!node.perturb(*scene, sampler, TransportMode::Radiance, dir, e, succ)) return 0.0;
        return solidAngleDensity(
            node, succ, node.evalPdf(*scene, &PathVertex::sensorSupernode(), succ, e, TransportMode::Radiance));
    };
    const Chi2Result r = chi2Sphere(sample, pdf, opt);
    EXPECT_TRUE(r.passed) << "sensor: " << r.report;
}

// Supernodes: positions on the emitters (selection by samplingWeight, then uniform by area) and on a thin
// lens, histogrammed against EVALPDF integrated over each cell.
TEST(PathSpace, SupernodeSampleNextMatchesEvalPdf) {
    auto scene = sceneFromXml("supernode", R"(
        <shape type="rectangle"><transform name="toWorld"><scale value="0.5"/></transform>
            <emitter type="area"><float name="samplingWeight" value="3"/></emitter></shape>
        <shape type="rectangle"><transform name="toWorld"><scale x="0.2" y="0.1" z="1"/><translate z="1"/></transform>
            <emitter type="area"/></shape>
        <emitter type="point"><point name="position" x="0" y="0" z="2"/></emitter>)");
    constexpr int kCells = 4, kDraws = 200000;
    // Cells: 4 x 4 on each rectangle (local coordinates in [-1, 1]^2), then the point light.
    const double halfX[2] = {0.5, 0.2}, halfY[2] = {0.5, 0.1};
    std::vector<double> observed(2 * kCells * kCells + 1, 0.0), expected(observed.size(), 0.0);
    PCG32 rng(11, 13);
    RngSampler sampler(rng);
    for (int i = 0; i < kDraws; ++i) {
        PathVertex supernode = PathVertex::emitterSupernode(), node;
        PathEdge edge;
        ASSERT_TRUE(supernode.sampleNext(*scene, sampler, TransportMode::Importance, nullptr, edge, node));
        const Vec3 p = node.position();
        size_t cell = observed.size() - 1;
        if (!node.hasDeltaPosition()) {
            const int k = p.z > 0.5 ? 1 : 0;
            const int cx = std::min(kCells - 1, static_cast<int>((p.x / halfX[k] + 1) * 0.5 * kCells));
            const int cy = std::min(kCells - 1, static_cast<int>((p.y / halfY[k] + 1) * 0.5 * kCells));
            cell = static_cast<size_t>((k * kCells + cy) * kCells + cx);
            // EVALPDF is uniform on each rectangle: density times the cell's area.
            const double cellArea = 4 * halfX[k] * halfY[k] / (kCells * kCells);
            expected[cell] = kDraws * node.pdf[modeIndex(TransportMode::Importance)] * cellArea;
        } else {
            expected[cell] = kDraws * node.pdf[modeIndex(TransportMode::Importance)];
        }
        EXPECT_DOUBLE_EQ(
            node.pdf[modeIndex(TransportMode::Importance)],
            PathVertex::emitterSupernode().evalPdf(*scene, nullptr, node, edge, TransportMode::Importance));
        observed[cell] += 1;
    }
    const Chi2Result r = chi2Histogram(observed, expected, 0.01, 2);
    EXPECT_TRUE(r.passed) << "emitter positions: " << r.report;

    // Thin lens of radius 0.05: cells of equal area in (r^2, phi).
    auto lens = loadScene(writeFile(tempDir("path-space-lens"), "scene.xml", R"(<scene version="0.6.0">
        <sensor type="thinlens"><float name="apertureRadius" value="0.05"/><float name="focusDistance" value="3"/>
            <transform name="toWorld"><lookat origin="1, 2, 3" target="0, 0, 0" up="0, 0, 1"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <shape type="sphere"><float name="radius" value="10"/></shape></scene>)"));
    const Sensor &sensor = lens->sensor();
    const Transform toLocal = sensor.toWorld().inverse();
    std::vector<double> obs(kCells * kCells, 0.0), exp(obs.size(), 0.0);
    for (int i = 0; i < kDraws; ++i) {
        PathVertex supernode = PathVertex::sensorSupernode(), node;
        PathEdge edge;
        ASSERT_TRUE(supernode.sampleNext(*lens, sampler, TransportMode::Radiance, nullptr, edge, node));
        const Vec3 a = toLocal.point(node.position());
        const double r2 = (a.x * a.x + a.y * a.y) / (0.05 * 0.05);
        double phi = std::atan2(a.y, a.x);
        if (phi < 0) phi += 2 * kPi;
        const size_t cell = static_cast<size_t>(std::min(kCells - 1, static_cast<int>(r2 * kCells)) * kCells +
                                                std::min(kCells - 1, static_cast<int>(phi / (2 * kPi) * kCells)));
        obs[cell] += 1;
        exp[cell] = kDraws * node.pdf[modeIndex(TransportMode::Radiance)] * kPi * 0.05 * 0.05 / (kCells * kCells);
    }
    const Chi2Result l = chi2Histogram(obs, exp, 0.01, 2);
    EXPECT_TRUE(l.passed) << "lens positions: " << l.report;
}

// Medium vertices: the scattered direction (Henyey-Greenstein) and the free-flight distance to the next
// vertex, through an index-matched boundary into vacuum.
TEST(PathSpace, MediumSampleNextMatchesEvalPdf) {
    auto scene = sceneFromXml("medium", R"(
        <medium type="homogeneous" id="fog"><rgb name="sigmaS" value="0.5, 1.5, 2.5"/><rgb name="sigmaA" value="0.5"/>
            <phase type="hg"><float name="g" value="0.5"/></phase></medium>
        <shape type="sphere"><float name="radius" value="1"/><ref name="interior" id="fog"/></shape>)");
    const Medium *fog = nullptr;
    for (const auto &shape : scene->shapes())
        if (shape->interiorMedium()) fog = shape->interiorMedium();
    ASSERT_NE(fog, nullptr);
    const PathVertex pred = pointVertex(Vec3(0.3, 0.0, -0.5));
    PathVertex cur = pointVertex(Vec3(0.0));
    cur.medium = fog;
    cur.its.wi = normalize(pred.position());

    // A medium successor at distance t along d, with the edge from cur as the walk of `mode` sees it.
    const auto successorAt = [&](const Vec3 &d, double t, TransportMode mode, PathEdge &edge) {
        PathVertex succ = pointVertex(d * t);
        succ.medium = fog;
        // connect() traces from the emitter side: the walk's start is the emitter side in importance mode.
        const bool ok =
            mode == TransportMode::Importance ? connect(*scene, cur, succ, edge) : connect(*scene, succ, cur, edge);
        EXPECT_TRUE(ok);
        return succ;
    };
    for (const TransportMode mode : kModes) {
        // Directions: EVALPDF with the edge's distance density divided out is the phase function's density.
        Chi2Options opt;
        opt.sampleCount = 100000;
        opt.testCount = 4;
        const auto sample = [&](PCG32 &rng, Vec3 &dir) {
            RngSampler sampler(rng);
            PathVertex v = cur, succ;
            PathEdge edge;
            if (!v.sampleNext(*scene, sampler, mode, &pred, edge, succ)) return false;
            dir = normalize(succ.position() - v.position());
            return true;
        };
        const auto pdf = [&](const Vec3 &dir) {
            PathEdge edge;
            const PathVertex succ = successorAt(dir, 0.5, mode, edge);
            return cur.evalPdf(*scene, &pred, succ, edge, mode) * 0.25 / edge.pdf[modeIndex(mode)];
        };
        const Chi2Result r = chi2Sphere(sample, pdf, opt);
        EXPECT_TRUE(r.passed) << "medium directions, " << modeName(mode) << ": " << r.report;

        // Distances: 20 cells on [0, 1) inside the fog, one for the surface beyond. The distance density
        // is EVALPDF times t^2 over the phase density (Simpson over each cell).
        constexpr int kCells = 20, kDraws = 200000;
        std::vector<double> observed(kCells + 1, 0.0), expected(kCells + 1, 0.0);
        PCG32 rng(17, 19);
        RngSampler sampler(rng);
        for (int i = 0; i < kDraws; ++i) {
            PathVertex v = cur, succ;
            PathEdge edge;
            if (!v.sampleNext(*scene, sampler, mode, &pred, edge, succ)) continue;
            const double t = (succ.position() - v.position()).length();
            observed[succ.type == VertexType::Medium ? std::min(kCells - 1, static_cast<int>(t * kCells)) : kCells] +=
                1;
        }
        const Vec3 d(0, 0, 1);
        const double phase = fog->phase().pdf(cur.its.wi, d);
        const auto density = [&](double t) {
            PathEdge edge;
            const PathVertex succ = successorAt(d, t, mode, edge);
            return cur.evalPdf(*scene, &pred, succ, edge, mode) * t * t / phase;
        };
        // Gauss-Legendre inside each cell: the densities are smooth there, and no node sits on t = 0.
        const double nodes[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563, 0.8611363115940526};
        const double weights[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461, 0.3478548451374538};
        for (int c = 0; c < kCells; ++c) {
            const double mid = (c + 0.5) / kCells, half = 0.5 / kCells;
            double acc = 0;
            for (int j = 0; j < 4; ++j) acc += weights[j] * density(mid + half * nodes[j]);
            expected[static_cast<size_t>(c)] = kDraws * acc * half;
        }
        // The surface beyond the fog's index-matched boundary: the enclosing sphere.
        PathVertex wall;
        PathEdge edge;
        ASSERT_TRUE(scene->intersect(Ray(d * 1.5, d), wall.its));
        const bool ok =
            mode == TransportMode::Importance ? connect(*scene, cur, wall, edge) : connect(*scene, wall, cur, edge);
        ASSERT_TRUE(ok);
        expected[kCells] = kDraws * solidAngleDensity(cur, wall, cur.evalPdf(*scene, &pred, wall, edge, mode)) / phase;
        const Chi2Result h = chi2Histogram(observed, expected, 0.01, 4);
        EXPECT_TRUE(h.passed) << "medium distances, " << modeName(mode) << ": " << h.report;
    }
}

// EVAL is the same vertex term whichever walk asks (ALGORITHMS.md §1.1): with shading normals that
// differ from the geometric one, the importance walk's adjoint BSDF times Veach's correction, over the
// geometric cosine towards the sensor side, equals the radiance walk's BSDF over the geometric cosine
// towards the emitter side. Smooth lobes only: Dirac weights differ by the solid-angle compression.
TEST(PathSpace, EvalIsTheSameForBothWalks) {
    const std::string dir = tempDir("path-space-shading");
    writeFile(dir, "tri.obj",
              "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nvn 0.3 0.2 1\nvn -0.2 0.4 1\nvn 0.1 -0.3 1\n"
              "f 1//1 2//2 3//3\n");
    const std::vector<std::string> bsdfs = {
        R"(<bsdf type="diffuse"/>)", R"(<bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf>)",
        R"(<bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="intIOR" value="1.33"/></bsdf>)"};
    for (const std::string &bsdf : bsdfs) {
        auto scene = loadScene(writeFile(dir, "scene.xml",
                                         R"(<scene version="0.6.0">
            <sensor type="perspective"><transform name="toWorld"><lookat origin="0, 0, 5" target="0, 0, 0"/></transform>
            </sensor><shape type="obj"><string name="filename" value="tri.obj"/>)" +
                                             bsdf + "</shape></scene>"));
        PathVertex v;
        ASSERT_TRUE(scene->intersect(Ray(Vec3(0.1, 0.0, 2.0), normalize(Vec3(0.05, 0.1, -1.0))), v.its));
        ASSERT_GT(std::abs(dot(v.its.n, v.its.shFrame.n) - 1.0), 1e-3) << "the shading normal must differ";
        PCG32 rng(5, 7);
        int compared = 0;
        for (int i = 0; i < 2000; ++i) {
            const Vec3 wl = warp::squareToUniformSphere(Vec2(rng.nextDouble(), rng.nextDouble()));
            const Vec3 wc = warp::squareToUniformSphere(Vec2(rng.nextDouble(), rng.nextDouble()));
            const PathVertex light = pointVertex(v.its.p + wl), camera = pointVertex(v.its.p + wc);
            const Spectrum imp = v.eval(*scene, &light, camera, TransportMode::Importance) / v.cosine(wc);
            const Spectrum rad = v.eval(*scene, &camera, light, TransportMode::Radiance) / v.cosine(wl);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(imp[c], rad[c], 1e-9 * std::max(1.0, rad[c])) << bsdf;
            if (!rad.isBlack()) ++compared;
        }
        EXPECT_GT(compared, 300) << bsdf;
    }
}

// A scene with every vertex and edge type, lit by an area light, a point light and `sky` (an environment
// or parallel light).
std::string kitchenSinkScene(const std::string &sky) {
    const std::string skyEmitter =
        sky == "directional"
            ? R"(<emitter type="directional"><vector name="direction" x="-0.3" y="-1" z="-0.2"/></emitter>)"
            : R"(<emitter type="constant"><spectrum name="radiance" value="0.2"/></emitter>)";
    return R"(<scene version="0.6.0">
        <integrator type="bdpt"><integer name="maxDepth" value="6"/></integrator>
        <sensor type="thinlens"><float name="apertureRadius" value="0.15"/><float name="focusDistance" value="4"/>
            <transform name="toWorld"><lookat origin="0, 1, 5" target="0, 0.8, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        <medium type="homogeneous" id="fog"><rgb name="sigmaS" value="0.6, 0.8, 1.0"/><rgb name="sigmaA" value="0.1"/>
            <phase type="hg"><float name="g" value="0.4"/></phase></medium>
        <shape type="rectangle"><transform name="toWorld"><scale value="3"/><rotate x="1" angle="-90"/></transform>
            <bsdf type="diffuse"/></shape>
        <shape type="rectangle"><transform name="toWorld"><scale value="3"/><translate z="-2"/></transform>
            <bsdf type="roughconductor"><float name="alpha" value="0.2"/></bsdf></shape>
        <shape type="cube"><transform name="toWorld"><scale value="0.5"/><translate x="1" y="0.5"/></transform>
            <ref name="interior" id="fog"/></shape>
        <shape type="sphere"><point name="center" x="-1" y="0.6" z="0"/><float name="radius" value="0.5"/>
            <bsdf type="dielectric"/></shape>
        <shape type="sphere"><point name="center" x="0" y="0.4" z="1"/><float name="radius" value="0.4"/>
            <bsdf type="plastic"/></shape>
        <shape type="sphere"><point name="center" x="-1.5" y="0.3" z="1.5"/><float name="radius" value="0.3"/>
            <bsdf type="roughdielectric"><float name="alpha" value="0.3"/></bsdf></shape>
        <shape type="rectangle"><transform name="toWorld"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="3"/>
            </transform><emitter type="area"><spectrum name="radiance" value="6"/></emitter></shape>
        <emitter type="point"><point name="position" x="1" y="2" z="1.5"/><spectrum name="intensity" value="3"/></emitter>
        )" +
           skyEmitter + "</scene>";
}

// Random paths as BDPT samples them (small films, the scene's maxDepth, at most 8). Russian roulette is
// off: its survival probabilities divide the walks' throughputs but are no part of f / p. `options` sets
// further BDPT parameters (the strategy set and the heuristic that the weights depend on).
void checkRandomPaths(Scene &scene, const std::vector<std::pair<std::string, bool>> &options = {},
                      const std::string &heuristic = "power") {
    scene.resizeFilm(8, 8);
    const int64_t depth = scene.integratorProperties().getInt("maxDepth", -1);
    Properties props(ObjectKind::Integrator, "bdpt", {});
    props.set("maxDepth", Properties::Type::Integer, depth < 0 ? int64_t(8) : std::min<int64_t>(depth, 8), {});
    props.set("rrDepth", Properties::Type::Integer, int64_t(100), {});
    for (const auto &[name, value] : options) props.set(name, Properties::Type::Boolean, value, {});
    props.set("heuristic", Properties::Type::String, heuristic, {});
    const BDPT bdpt(props);
    int paths = 0, identities = 0;
    std::vector<double> pFwd, pRev;
    PathDensities stored;
    for (uint64_t pixel = 0; pixel < 64; ++pixel)
        for (uint64_t index = 0; index < 4; ++index) {
            IndependentSampler sampler(21, pixel, index);
            const Vec2 raster(static_cast<double>(pixel % 8) + sampler.next1D(),
                              static_cast<double>(pixel / 8) + sampler.next1D());
            bdpt.evaluate(scene, sampler, raster, [&](const StrategySample &x) {
                ++paths;
                const MutablePath full(*x.path);
                const int n = full.length(), s = x.s;
                // Well formed: emitter node, scattering vertices, sensor node.
                EXPECT_EQ(full.vertex(0).type, VertexType::EmitterNode);
                EXPECT_EQ(full.vertex(n - 1).type, VertexType::SensorNode);
                for (int i = 1; i + 1 < n; ++i)
                    EXPECT_FALSE(full.vertex(i).isEndpointNode() || full.vertex(i).isSupernode());
                evalDensities(scene, full, pFwd, pRev);
                const MISOptions &opt = bdpt.misOptions();
                // What BDPT keeps and caches (the junction's densities from the connection, the direct
                // densities from the walks or the direct sample) is what EVALPDF and directDensity give.
                x.path->densities(scene, opt.sampleDirect, stored);
                for (int i = 0; i < n; ++i) {
                    EXPECT_EQ(stored.pFwd[static_cast<size_t>(i)], pFwd[static_cast<size_t>(i)])
                        << "p->(x_" << i << ") s=" << s << " t=" << x.t;
                    EXPECT_EQ(stored.pRev[static_cast<size_t>(i)], pRev[static_cast<size_t>(i)])
                        << "p<-(x_" << i << ") s=" << s << " t=" << x.t;
                    EXPECT_EQ(stored.connectable[static_cast<size_t>(i)] != 0, full.vertex(i).isConnectable());
                }
                if (opt.sampleDirect && n >= 3) {
                    EXPECT_EQ(stored.directEmitter, directDensity(scene, full.vertex(0), full.vertex(1)))
                        << "s=" << s << " t=" << x.t;
                    EXPECT_EQ(stored.directSensor, directDensity(scene, full.vertex(n - 1), full.vertex(n - 2)))
                        << "s=" << s << " t=" << x.t;
                }
                const std::vector<double> p = strategyDensities(scene, full, pFwd, pRev, opt);
                ASSERT_GT(p[static_cast<size_t>(s)], 0.0) << "the strategy that produced the path must be possible";
                double sumPow = 0, sumWeights = 0;
                for (const double pr : p) sumPow += std::pow(pr, opt.exponent);
                for (int r = 0; r <= n; ++r) {
                    const double w = misWeight(scene, full, r, pFwd, pRev, opt);
                    const double explicitWeight = std::pow(p[static_cast<size_t>(r)], opt.exponent) / sumPow;
                    if (p[static_cast<size_t>(r)] > 0) {
                        EXPECT_NEAR(w, explicitWeight, 1e-9) << "r=" << r << " of n=" << n;
                        sumWeights += w;
                    }
                }
                EXPECT_NEAR(sumWeights, 1.0, 1e-9) << "s=" << s << " t=" << x.t;
                EXPECT_NEAR(x.weight, misWeight(scene, full, s, pFwd, pRev, opt), 1e-12);
                // The estimate of strategy s is f / p_s. The walks weigh the directions they sampled, EVAL and
                // EVALPDF the directions between vertex positions, which differ by the offset of spawned rays
                // over the edge length: at most the two ends' offsets over it. A glossy lobe varies by up to ~100
                // per radian, a diffuse one or an endpoint's profile by about 1, so the expected difference is bounded
                // by the largest angle times that at either end of its edge; the check runs where the bound is below
                // 1% (a path of veach-bidir's with 1.3e-3 radians at a glossy vertex was 2.2% off). A missing cosine,
                // adjoint or eta^2 factor is off by far more.
                const auto sensitivity = [&](int i) {
                    const PathVertex &v = full.vertex(i);
                    return v.type == VertexType::Surface && (v.its.bsdf()->flags() & BSDFFlags::Glossy) ? 100.0 : 1.0;
                };
                double bound = 0;
                for (int i = 0; i + 1 < n; ++i)
                    bound = std::max(bound, (scene.epsilonAt(full.vertex(i).position()) +
                                             scene.epsilonAt(full.vertex(i + 1).position())) /
                                                full.edge(i).length * std::max(sensitivity(i), sensitivity(i + 1)));
                if (bound > 1e-2) return;
                const Spectrum expected = contribution(scene, full) / p[static_cast<size_t>(s)];
                const Spectrum &got = x.path->contribution();
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(got[c], expected[c], 2e-2 * std::max(got[c], 1e-12)) << "s=" << s << " t=" << x.t;
                ++identities;
            });
        }
    EXPECT_GT(paths, 100) << "too few paths to mean anything";
    std::printf("%d paths, %d of them checked against f / p\n", paths, identities);
    EXPECT_GT(identities, paths / 4) << "too few well-conditioned paths for the f / p check";
}

class SharedScenePaths : public ::testing::TestWithParam<std::string> {};

TEST_P(SharedScenePaths, MisWeightsSumToOne) {
    auto scene = loadScene(std::string(PATHFARM_SOURCE_DIR) + "/scenes/" + GetParam() + "/scene.xml");
    checkRandomPaths(*scene);
}

// Every vertex and edge type at once: a thin lens (the t = 0 strategy), an area light, a point light
// behind the camera, an environment, an index-matched box of fog, and Dirac, glossy, mixed and
// refractive surfaces.
TEST(PathSpace, KitchenSinkPathsMisWeightsSumToOne) {
    auto scene = loadScene(writeFile(tempDir("path-space-sink"), "scene.xml", kitchenSinkScene("constant")));
    checkRandomPaths(*scene);
}

// The same with the other strategy sets and the balance heuristic: BDPT's weights, from the densities it
// keeps, against the explicit densities of each strategy.
TEST(PathSpace, KitchenSinkWeightsForEveryStrategySet) {
    auto scene = loadScene(writeFile(tempDir("path-space-sets"), "scene.xml", kitchenSinkScene("constant")));
    checkRandomPaths(*scene, {{"sampleDirect", false}});
    checkRandomPaths(*scene, {{"lightImage", false}});
    checkRandomPaths(*scene, {{"sampleDirect", false}, {"lightImage", false}}, "balance");
}

// Parallel light (a delta direction): the s = 1 strategy exists only through direct sampling.
TEST(PathSpace, DirectionalLightPathsMisWeightsSumToOne) {
    auto scene = loadScene(writeFile(tempDir("path-space-sun"), "scene.xml", kitchenSinkScene("directional")));
    checkRandomPaths(*scene);
}

INSTANTIATE_TEST_SUITE_P(Scenes, SharedScenePaths,
                         ::testing::Values("cornell-box", "veach-mis", "veach-bidir", "ring-caustic",
                                           "volumetric-caustic"),
                         [](const ::testing::TestParamInfo<std::string> &info) {
                             std::string name = info.param;
                             for (char &c : name)
                                 if (c == '-') c = '_';
                             return name;
                         });

}  // namespace
}  // namespace pf::test
