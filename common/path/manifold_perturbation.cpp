#include "path/manifold_perturbation.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "core/frame.h"
#include "core/sincos.h"
#include "manifold/generalized_geometry.h"
#include "manifold/offset_jacobian.h"
#include "manifold/roughness.h"
#include "path/perturbation.h"
#include "scene/medium.h"
#include "scene/scene.h"

namespace pf {

namespace {

// Paths traced through the scene lie off the specular manifold by a few ray offsets: every ray of the path-space
// random walks and of propagate() starts Scene::epsilonAt() off its surface along the normal, which moves the
// rest of a specular chain sideways. Walks, by contrast, converge onto the manifold to 1e-7 of the scene scale.
// So a chain traced from x_c through the walked chain lands near, not on, the walked vertices, and the reverse
// walk returns near, not onto, x's stored chain. Both comparisons below allow this many ray offsets at the vertex
// compared (measured: up to about 10 on TORUS and veach-bidir, rarely 100 near caustic folds; another branch of
// the manifold lies much further away).
constexpr double kRayOffsets = 100;

TransportMode walkMode(int dir) { return dir > 0 ? TransportMode::Importance : TransportMode::Radiance; }

// Endpoint nodes a strategy can use: a position on a shape, or a point (the environment has neither).
bool usableEnd(const PathVertex &v) {
    return v.type != VertexType::EmitterNode || v.its.shape != nullptr || v.hasDeltaPosition();
}

// The chain x_from .. x_to of path p for WalkManifold, the generalized geometry term and the offset
// Jacobian: non-specular ends, the unconstrained x_b at index `free` (if any), and constrained vertices in
// between, ideal specular ones with o = 0 and the glossy ones with their current offsets (§6.6), in order
// from `from`.
std::optional<std::vector<ManifoldVertex>> manifoldChain(const PathView &p, int from, int to, int free = -1) {
    const int dir = to > from ? 1 : -1;
    std::vector<ManifoldVertex> chain;
    const auto first = ManifoldVertex::endpoint(p.vertex(from), p.vertex(from + dir).position());
    if (!first) return std::nullopt;
    chain.push_back(*first);
    for (int i = from + dir; i != to; i += dir) {
        const PathVertex &v = p.vertex(i);
        const Vec3 &prev = p.vertex(i - dir).position(), &next = p.vertex(i + dir).position();
        const auto mv = i == free ? ManifoldVertex::surface(v.its)
                        : v.type == VertexType::Medium
                            ? ManifoldVertex::medium(v.position(), prev, next)
                            : ManifoldVertex::constrained(v.its, prev, next, !isNonSpecular(v));
        if (!mv) return std::nullopt;
        chain.push_back(*mv);
    }
    const auto last = ManifoldVertex::endpoint(p.vertex(to), p.vertex(to - dir).position());
    if (!last) return std::nullopt;
    chain.push_back(*last);
    return chain;
}

// The next vertex after `cur` (towards `end`) that is not ideal specular in x, or `end`.
int nextSmooth(const PathView &x, int cur, int end) {
    const int dir = end > cur ? 1 : -1;
    int next = cur + dir;
    while (next != end && !isNonSpecular(x.vertex(next))) next += dir;
    return next;
}

// The held segment of chain vertex `v` of x reached from direction dir (§6.7): its distance to its predecessor
// when it is a medium vertex of the chain, 0 otherwise (the propagation then ends as the walk samples it).
double heldSegment(const PathView &x, int v, int dir, int moving) {
    if (v == moving || x.vertex(v).type != VertexType::Medium) return 0.0;
    return (x.vertex(v).position() - x.vertex(v - dir).position()).length();
}

// Vertices that can be x_b: surfaces, and medium vertices (§6.7: a medium vertex is a non-specular vertex like any
// other; without it, a path that the camera sees through glass into a medium, E S M .., could never move on the
// film).
bool movable(const PathVertex &v) { return v.type == VertexType::Surface || v.type == VertexType::Medium; }

// The walk's target for x_b at v: a surface point, or a medium point on the plane facing `toward` (§6.7).
std::optional<ManifoldVertex> walkTarget(const PathVertex &v, const Vec3 &toward) {
    return v.type == VertexType::Medium ? ManifoldVertex::mediumEndpoint(v.position(), toward)
                                        : ManifoldVertex::surface(v.its);
}

// Whether strategy st can move x's x_b: a medium x_b only with ideal specular chains on both sides, since the
// offset Jacobian (manifold/offset_jacobian.h) holds a surface x_b between held glossy or medium vertices, not a
// free point of a volume. Such a classification is a failed proposal, like an unusable x_b.
bool supportedMove(const PathView &x, int source, int moving, int fixed) {
    if (x.vertex(moving).type != VertexType::Medium) return true;
    const int dir = fixed > source ? 1 : -1;
    for (int i = source + dir; i != fixed; i += dir)
        if (i != moving && isNonSpecular(x.vertex(i))) return false;
    return true;
}

bool onFilm(const Film &film, const Vec2 &raster) {
    return raster.x >= 0 && raster.y >= 0 && raster.x < film.cropWidth() && raster.y < film.cropHeight();
}

// A sensor node that sends its ray in direction d gets the raster position d enters the film at.
bool aimSensor(const Scene &scene, PathVertex &v, const Vec3 &d) {
    if (v.type != VertexType::SensorNode) return true;
    Vec2 raster;
    if (!scene.sensor().rasterPosition(v.position(), d, raster) || !onFilm(scene.sensor().film(), raster)) return false;
    v.ps.uv = raster;
    return true;
}

// Whether the source is a supernode: the move then offsets the position of the endpoint node after it.
bool isPositionSource(const PathView &x, int source) { return source < 0 || source >= x.length(); }

// Endpoint nodes whose position the endpoint position perturbation moves (§6.5): a point on an area
// emitter or on a finite aperture.
bool perturbablePosition(const PathVertex &v) {
    return v.isEndpointNode() && !v.hasDeltaPosition() && (v.type == VertexType::SensorNode || v.its.shape);
}

// How far a point found on an emitter or aperture may lie off the plane of the node it was offset from:
// planar lights and apertures keep it within the ray-offset noise.
double offPlaneTolerance(const Scene &scene, const Vec3 &p) { return 10 * scene.epsilonAt(p); }

// The endpoint node of v's emitter or aperture at point p of v's tangent plane, into `out`: found by a ray
// along the normal from just in front of the plane. Only planar lights and apertures are perturbed: the
// point must lie on v's plane with v's normal, so that the tangential offset is the area measure's own
// coordinate and the kernel is symmetric (a curved light fails the move).
bool placeEndpoint(const Scene &scene, const PathVertex &v, const Vec3 &p, PathVertex &out) {
    const Vec3 &n = v.ps.n;
    const double h = offPlaneTolerance(scene, p);
    const Ray ray(p + n * h, -n, 0, 2 * h);
    PositionSample ps;
    if (v.type == VertexType::SensorNode) {
        double t;
        if (!scene.sensor().intersectAperture(ray, ps, t)) return false;
        out = PathVertex::endpointNode(scene, ps, nullptr);
        out.medium = v.medium;
    } else {
        Intersection its;
        if (!scene.intersect(ray, its) || its.shape != v.its.shape || its.emitter() != v.emitter) return false;
        out = PathVertex();
        out.its = its;
        out.medium = v.medium;
        if (!out.cast(scene, VertexType::EmitterNode)) return false;
        ps = out.ps;
    }
    out.walkMode = v.walkMode;
    return std::abs(dot(ps.p - v.position(), n)) <= h && dot(ps.n, n) > 1 - 1e-9;
}

// The direction of the ray from `from` through point p, as rayDirection() measures it.
Vec3 rayDirectionTo(const Scene &scene, const PathVertex &from, const Vec3 &p) {
    PathVertex to;
    to.its.p = p;
    return rayDirection(scene, from, to);
}

}  // namespace

ManifoldPerturbation::ManifoldPerturbation(const Scene &scene, double lambda, double glossyAngle, bool mediumChains,
                                           double mediumAngle)
    : lambda_(lambda),
      glossyAngle_(glossyAngle),
      mediumChains_(mediumChains),
      mediumAngle_(mediumAngle < 0 ? glossyAngle : mediumAngle),
      walk_(scene) {}

// rho = G(u <-> ... <-> l) / (|cos_u| J(u -> l)) of y's chain between `end` and `moving` (header). G is
// taken over the chain listed from u: generalizedGeometry(x_1 .. x_k) is the Jacobian of projected solid angle
// at x_1 per area at x_k, which through a refraction differs from the reverse one by the ratio of the squared
// indices (etendue), and the canonical density it is compared with is the sensor walk's from u. |cos_u| J's
// first step is written with the chain's own geometry term, so that endpoint conventions (points have no
// cosine) match G's.
double ManifoldPerturbation::measureRatio(const PathView &y, int end, int moving) {
    const int hi = std::max(end, moving), lo = std::min(end, moving);
    const auto chain = manifoldChain(y, hi, lo);
    if (!chain) return 0.0;
    const std::optional<double> g = generalizedGeometry(*chain);
    const PathVertex &b = y.vertex(hi - 1);
    const Vec3 ab = b.position() - y.vertex(hi).position();
    const double firstStep = b.cosine(normalize(ab)) / ab.lengthSquared();
    const double rest = propagationJacobian(y, hi, lo, TransportMode::Radiance) / firstStep;
    const double denominator = geometryTerm((*chain)[0], (*chain)[1]) * rest;
    return g && denominator > 0 ? *g / denominator : 0.0;
}

// The edges are traced from `from` (the walk's mode); rho converts the ideal sub-chains' measure; 0 when
// degenerate.
double ManifoldPerturbation::toCanonical(const PathView &y, int from, int moving, bool placedEnd) {
    const int dir = moving > from ? 1 : -1, mode = modeIndex(walkMode(dir));
    double factor = 1.0;
    for (int u = from; u != moving && factor > 0;) {
        const int w = nextSmooth(y, u, moving);
        // The walk's own probability of crossing each traced edge (free-flight survival), except that an edge
        // into a medium vertex of the chain is placed at its held length, not sampled (§6.7); rho holds the
        // sensor walk's densities instead, which differ from these at medium ends.
        const bool held =
            heldSegment(y, w, dir, moving) > 0 || (placedEnd && w == moving && y.vertex(w).type == VertexType::Medium);
        double walked = 1.0, sensor = 1.0;
        for (int e = u; e != w; e += dir) {
            const PathEdge &edge = y.edge(std::min(e, e + dir));
            if (!held || e + dir != w) walked *= edge.pdf[mode];
            sensor *= edge.pdf[modeIndex(TransportMode::Radiance)];
        }
        if (std::abs(w - u) > 1) {
            const double rho = measureRatio(y, u, w);
            factor = rho > 0 && sensor > 0 ? factor / rho * (walked / sensor) : 0.0;
        } else {
            factor *= walked;
        }
        u = w;
    }
    return factor;
}

double ManifoldPerturbation::offsetFactor(const PathView &y, const Strategy &st) {
    // A position source has no first chain: the chain starts at the endpoint node x_b, held as an end.
    const int from = isPositionSource(y, st.source) ? st.moving : st.source;
    std::vector<size_t> glossy;
    for (int u = from; u != st.fixed;) {
        const int w = nextSmooth(y, u, st.fixed);
        if (w != st.fixed && w != st.moving) glossy.push_back(static_cast<size_t>(std::abs(w - from)));
        u = w;
    }
    if (glossy.empty()) return 1.0;
    const auto chain = manifoldChain(y, from, st.fixed, from == st.moving ? -1 : st.moving);
    const std::optional<double> j =
        chain ? offsetJacobian(*chain, static_cast<size_t>(std::abs(st.moving - from)), glossy) : std::nullopt;
    return j ? *j : 0.0;
}

double ManifoldPerturbation::measureConversion(const PathView &y, const Strategy &st) const {
    double r = 1.0;
    for (const int end : {st.source, st.fixed})
        for (int u = end; u != st.moving;) {
            const int w = nextSmooth(y, u, st.moving);
            if (std::abs(w - u) > 1) r *= measureRatio(y, u, w);
            u = w;
        }
    return r * offsetFactor(y, st);
}

double ManifoldPerturbation::chainProbability(const PathVertex &v) const {
    if (!isNonSpecular(v)) return 1.0;
    // A medium vertex: the Henyey-Greenstein median scattering angle against dtheta ([TR A1], §6.6).
    if (v.type == VertexType::Medium)
        return mediumChains_ && v.medium && mediumAngle_ > 0
                   ? specularProbability(hgQuantileAngle(v.medium->phase().meanCosine()), mediumAngle_)
                   : 0.0;
    if (!(glossyAngle_ > 0)) return 0.0;
    if (v.type != VertexType::Surface) return 0.0;
    const BSDF *bsdf = v.its.bsdf();
    if (!(bsdf->flags() & BSDFFlags::Glossy) || (bsdf->flags() & BSDFFlags::Diffuse)) return 0.0;
    return 1 - nonSpecularProbabilitySurface(bsdf->roughness(v.its, BSDFFlags::Glossy), glossyAngle_);
}

double ManifoldPerturbation::classificationProbability(const PathView &x, const Strategy &st) const {
    const int dir = st.fixed > st.source ? 1 : -1;
    double p = 1 - chainProbability(x.vertex(st.fixed));
    for (int i = st.source + dir; i != st.fixed; i += dir) {
        const double psi = chainProbability(x.vertex(i));
        p *= i == st.moving ? 1 - psi : psi;
    }
    return p;
}

std::vector<ManifoldPerturbation::Source> ManifoldPerturbation::sources(const PathView &x) const {
    const int n = x.length();
    const auto inPath = [n](int i) { return i >= 0 && i < n; };
    // Whether some classification of the vertices after x_b finds x_c.
    const auto reachableEnd = [&](int b, int dir) {
        for (int c = b + dir; inPath(c); c += dir) {
            const double psiC = chainProbability(x.vertex(c));
            if (psiC < 1 && usableEnd(x.vertex(c))) return true;
            if (psiC <= 0) break;
        }
        return false;
    };
    // Whether some classification of the vertices after `s` finds x_b and x_c.
    const auto reachable = [&](int s, int dir) {
        for (int b = s + dir; inPath(b); b += dir) {
            const double psiB = chainProbability(x.vertex(b));
            if (psiB < 1 && movable(x.vertex(b)) && reachableEnd(b, dir)) return true;
            if (psiB <= 0) return false;
        }
        return false;
    };
    std::vector<Source> list;
    for (int s = 0; s < n; ++s) {
        if (!isNonSpecular(x.vertex(s)) || !usableEnd(x.vertex(s))) continue;
        for (const int dir : {1, -1})
            if (reachable(s, dir)) list.push_back({s, dir});
    }
    // The supernodes, whose move offsets the position of the light or aperture node (§6.5).
    if (perturbablePosition(x.vertex(0)) && reachableEnd(0, 1)) list.push_back({-1, 1});
    if (perturbablePosition(x.vertex(n - 1)) && reachableEnd(n - 1, -1)) list.push_back({n, -1});
    return list;
}

std::optional<ManifoldPerturbation::Strategy> ManifoldPerturbation::classify(Sampler &sampler, const PathView &x,
                                                                             const Source &source) const {
    // A position source moves the endpoint node itself.
    int moving = isPositionSource(x, source.vertex) ? source.vertex + source.dir : -1;
    for (int j = (moving >= 0 ? moving : source.vertex) + source.dir; j >= 0 && j < x.length(); j += source.dir) {
        const double psi = chainProbability(x.vertex(j));
        if (psi >= 1 || (psi > 0 && sampler.next1D() < psi)) continue;
        if (moving >= 0) {
            if (!usableEnd(x.vertex(j))) return std::nullopt;
            if (!supportedMove(x, source.vertex, moving, j)) return std::nullopt;
            return Strategy{source.vertex, moving, j};
        }
        if (!movable(x.vertex(j))) return std::nullopt;
        moving = j;
    }
    return std::nullopt;
}

bool ManifoldPerturbation::applies(const PathView &x) const { return !sources(x).empty(); }

ManifoldPerturbation::GaussianOffset ManifoldPerturbation::positionKernel(const Scene &scene,
                                                                          const PathVertex &v) const {
    // The node's ps.pdf depends on which walk made it (direct sampling leaves another measure): evaluate.
    const double uniform =
        v.type == VertexType::SensorNode ? scene.sensor().pdfPosition(v.ps) : v.emitter->pdfPosition(v.ps);
    const double area = uniform > 0 ? 1 / uniform : 0.0;
    return {area / (2 * kPi * lambda_ * lambda_)};
}

Vec2 ManifoldPerturbation::GaussianOffset::sample(const Vec2 &u) const {
    // Box-Muller.
    const double r = std::sqrt(-2 * variance * std::log1p(-u.x));
    const SinCos phi = sinCos2Pi(u.y);
    return {r * phi.cos, r * phi.sin};
}

double ManifoldPerturbation::GaussianOffset::eval(const Vec2 &offset) const {
    if (!(variance > 0)) return 0.0;
    return std::exp(-(offset.x * offset.x + offset.y * offset.y) / (2 * variance)) / (2 * kPi * variance);
}

VonMisesFisher ManifoldPerturbation::kernel(const Scene &scene, const PathView &x, int source, int dir) const {
    // p(w_i -> w_o): x_s's own sampling density of its successor, per unit area there, back to solid angle.
    const TransportMode mode = walkMode(dir);
    const PathVertex &v = x.vertex(source), &pred = x.vertex(source - dir), &succ = x.vertex(source + dir);
    const PathEdge &edge = x.edge(std::min(source, source + dir));
    const Vec3 toSucc = succ.position() - v.position();
    const double jacobian = succ.cosine(normalize(toSucc)) / toSucc.lengthSquared() * edge.pdf[modeIndex(mode)];
    const double area = v.evalPdf(scene, pred.isSupernode() ? nullptr : &pred, succ, edge, mode);
    const double p = jacobian > 0 ? area / jacobian : 0.0;
    // D(w_o) = lambda^2 p, with p >= 1/(4 pi) as in Mitsuba (flatter than uniform has no vMF, §6.8).
    return VonMisesFisher::fromPeakDensity(lambda_ * lambda_ * std::max(p, 1 / (4 * kPi)));
}

bool ManifoldPerturbation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                  MutationRecord &record) const {
    const std::vector<Source> list = sources(x);
    if (list.empty()) return false;
    const size_t pick = std::min(list.size() - 1, static_cast<size_t>(sampler.next1D() * list.size()));
    const Source source = list[pick];
    const Vec2 u = sampler.next2D();
    const std::optional<Strategy> st = classify(sampler, x, source);
    if (!st) return false;
    record = {std::min(st->source, st->fixed), std::max(st->source, st->fixed), std::abs(st->fixed - st->source) - 1,
              st->source, st->moving};
    y = x;
    if (isPositionSource(x, source.vertex)) {
        // Endpoint position perturbation: a tangential Gaussian offset of the light or aperture node.
        const PathVertex &v = x.vertex(st->moving);
        Vec3 s, t;
        coordinateSystem(v.ps.n, s, t);
        const Vec2 offset = positionKernel(scene, v).sample(u);
        if (!placeEndpoint(scene, v, v.position() + s * offset.x + t * offset.y, y.vertex(st->moving))) return false;
        // The aperture takes no walk: a chain seen through the lens would have to land on the lens plane.
        if (v.type == VertexType::SensorNode && std::abs(st->fixed - st->moving) > 1) return false;
    } else {
        const Vec3 mean = rayDirection(scene, x.vertex(source.vertex), x.vertex(source.vertex + source.dir));
        const Vec3 d = kernel(scene, x, source.vertex, source.dir).sample(mean, u);
        if (!aimSensor(scene, y.vertex(st->source), d) || !propagateChain(scene, sampler, x, y, *st, d)) return false;
    }
    if (std::abs(st->fixed - st->moving) == 1) return connectJunction(scene, y, std::min(st->moving, st->fixed));
    return connectChain(scene, sampler, x, y, *st);
}

bool ManifoldPerturbation::propagateChain(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                          const Strategy &st, Vec3 d) const {
    const int dir = st.moving > st.source ? 1 : -1;
    const auto chain = manifoldChain(x, st.source, st.moving);
    if (!chain) return false;
    for (int cur = st.source;;) {
        // Through the Dirac lobes up to the next glossy or medium vertex (at its held segment) or x_b.
        const int next = nextSmooth(x, cur, st.moving);
        if (!propagate(scene, sampler, walkMode(dir), x, y, cur, next, d, heldSegment(x, next, dir, st.moving)))
            return false;
        if (next == st.moving) return true;
        // A glossy vertex: scatter about the microfacet normal of x's offset (§6.6), as the walk's corrector
        // does, from the predecessor's position, so that y's offset is x's; a medium vertex: leave in the
        // direction of x's offset in the frame of the new incoming direction (§6.7).
        countChainVertex(x.vertex(next));
        const size_t i = static_cast<size_t>(std::abs(next - st.source));
        const Vec3 &from = y.vertex(next - dir).position(), &at = y.vertex(next).position();
        const auto traced = walk_.propagate({ManifoldVertex::fixedPosition(from), (*chain)[i], (*chain)[i + 1]}, from,
                                            normalize(at - from), nullptr);
        if (!traced) return false;
        // The path's ray leaves from an offset origin (Scene::spawnRay): aim it at the point the exact ray hits.
        d = rayDirectionTo(scene, y.vertex(next), (*traced)[2].p);
        cur = next;
    }
}

bool ManifoldPerturbation::connectChain(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                        const Strategy &st) const {
    // WalkManifold(x_c, ..., x_b -> x'_b): the fixed end plays x_1 (§6.4).
    const int dir = st.moving > st.fixed ? 1 : -1;
    const PathVertex &moved = y.vertex(st.moving);
    const auto chain = manifoldChain(x, st.fixed, st.moving);
    const Vec3 &neighbour = x.vertex(st.moving - dir).position();
    const auto target = walkTarget(moved, neighbour);
    if (!chain || !target || !isNonSpecular(moved)) return false;
    const WalkResult walked = walk_.walk(*chain, *target);
    stats_.walks += 1;
    stats_.iterations += walked.stats.iterations;
    stats_.chainVertices += walked.stats.chainSize;
    stats_.maxChainVertices = std::max(stats_.maxChainVertices, static_cast<double>(walked.stats.chainSize));
    if (!walked.converged()) return false;
    stats_.converged += 1;

    // The path-space vertices of the new chain: traced from x_c towards each walked glossy vertex and x'_b in
    // turn, each ideal specular vertex on the way keeping its Dirac lobe; every traced vertex must land where
    // the walk put it.
    MutablePath traced = y;
    Vec3 d = rayDirectionTo(scene, traced.vertex(st.fixed), walked.chain[1].p);
    if (!aimSensor(scene, traced.vertex(st.fixed), d)) return false;
    for (int cur = st.fixed;;) {
        const int next = nextSmooth(x, cur, st.moving);
        const size_t i = static_cast<size_t>(std::abs(next - st.fixed));
        // A medium x'_b is placed where the walk put it, not sampled (toCanonical()'s placed end).
        const double held = next == st.moving && moved.type == VertexType::Medium
                                ? (walked.chain[i].p - walked.chain[i - 1].p).length()
                                : heldSegment(x, next, dir, st.moving);
        if (!propagate(scene, sampler, walkMode(dir), x, traced, cur, next, d, held) ||
            (traced.vertex(next).position() - walked.chain[i].p).length() >
                kRayOffsets * scene.epsilonAt(walked.chain[i].p))
            return false;
        if (next == st.moving) break;
        countChainVertex(x.vertex(next));
        d = rayDirectionTo(scene, traced.vertex(next), walked.chain[i + 1].p);
        cur = next;
    }
    y.vertex(st.fixed).ps.uv = traced.vertex(st.fixed).ps.uv;
    for (int i = st.fixed + dir; i != st.moving; i += dir) y.vertex(i) = traced.vertex(i);
    bool crosses = false;
    for (int i = std::min(st.fixed, st.moving); i < std::max(st.fixed, st.moving); ++i) {
        y.edge(i) = traced.edge(i);
        crosses = crosses || y.edge(i).crossings > 0;
    }
    stats_.crossingWalks += crosses;

    // The reverse walk must bring the chain back to x's (mandatory, §6.5).
    const auto back = manifoldChain(y, st.fixed, st.moving);
    const auto origin = walkTarget(x.vertex(st.moving), neighbour);
    if (!back || !origin) return false;
    const WalkResult returned = walk_.walk(*back, *origin);
    stats_.reverseWalks += 1;
    const Vec3 &first = x.vertex(st.fixed + dir).position();
    if (!returned.converged() || (returned.chain[1].p - first).length() > kRayOffsets * scene.epsilonAt(first)) {
        stats_.nonReversible += 1;
        return false;
    }
    return true;
}

double ManifoldPerturbation::density(const Scene &scene, const PathView &x, const PathView &y,
                                     const MutationRecord &record) const {
    const int n = x.length();
    if (record.moving < 0 || y.length() != n) return 0.0;
    const int source = record.source, fixed = source == record.l ? record.m : record.l;
    const Strategy st{source, record.moving, fixed};
    const int dir = fixed > source ? 1 : -1;
    if ((st.moving - source) * dir <= 0 || (fixed - st.moving) * dir <= 0) return 0.0;
    if (!supportedMove(x, source, st.moving, fixed)) return 0.0;
    const std::vector<Source> list = sources(x);
    if (std::none_of(list.begin(), list.end(), [&](const Source &s) { return s.vertex == source && s.dir == dir; }))
        return 0.0;
    // y must have x's configuration over the range the move changed.
    for (int i = std::max(std::min(source, fixed), 0); i <= std::min(std::max(source, fixed), n - 1); ++i)
        if (isNonSpecular(x.vertex(i)) != isNonSpecular(y.vertex(i))) return 0.0;
    const double strategy = classificationProbability(x, st) / static_cast<double>(list.size());
    if (!(strategy > 0)) return 0.0;
    // The second chain, found by the walk; a junction x_b x_c is a deterministic connection.
    const double second = std::abs(fixed - st.moving) > 1 ? toCanonical(y, fixed, st.moving, true) : 1.0;
    if (isPositionSource(x, source)) {
        // The Gaussian offset's density per unit area of the (planar) light or aperture.
        const PathVertex &v = x.vertex(st.moving), &w = y.vertex(st.moving);
        const Vec3 delta = w.position() - v.position();
        if (w.type != v.type || w.its.shape != v.its.shape ||
            std::abs(dot(delta, v.ps.n)) > offPlaneTolerance(scene, w.position()))
            return 0.0;
        Vec3 s, t;
        coordinateSystem(v.ps.n, s, t);
        const double j = offsetFactor(y, st);
        return j > 0 ? strategy * positionKernel(scene, v).eval(Vec2(dot(delta, s), dot(delta, t))) * second / j : 0.0;
    }
    // T_M: the vMF density of the new direction per projected solid angle at x_a, times G through the first
    // chain (seen from x_a) per unit area at x'_b.
    const double lobe = kernel(scene, x, source, dir)
                            .eval(rayDirection(scene, x.vertex(source), x.vertex(source + dir)),
                                  rayDirection(scene, y.vertex(source), y.vertex(source + dir)));
    // The first chain: x'_b's canonical density per solid angle at x_a.
    double first;
    if (nextSmooth(y, source, st.moving) == st.moving) {
        // Ideal specular: the traced pseudo-measure itself, converted where the emitter walk traced it.
        first = propagationJacobian(y, source, st.moving, walkMode(dir));
        if (dir > 0)
            for (int i = source + 1; i < st.moving; ++i) first *= importanceToCanonical(scene, y, i);
    } else {
        // Through glossy vertices: G_o / |cos_a| on the offset manifold, to the canonical measure.
        const auto chain = manifoldChain(y, source, st.moving);
        const std::optional<double> g = chain ? generalizedGeometry(*chain) : std::nullopt;
        if (!g) return 0.0;
        // The cosine at x_a in G's convention (points and medium vertices have none).
        const ManifoldVertex &a = (*chain)[0];
        const double cosine =
            a.type == ManifoldVertexType::Surface ? absDot(a.ng, normalize((*chain)[1].p - a.p)) : 1.0;
        first = cosine > 0 ? *g / cosine * toCanonical(y, source, st.moving) : 0.0;
    }
    // The offset Jacobian at y (1 without glossy chain vertices).
    const double j = offsetFactor(y, st);
    return j > 0 ? strategy * lobe * first * second / j : 0.0;
}

void ManifoldPerturbation::countChainVertex(const PathVertex &v) const {
    (v.type == VertexType::Medium ? stats_.mediumVertices : stats_.glossySpecular) += 1;
}

void ManifoldPerturbation::addCounters(ChainCounters &counters) const {
    counter(counters, "manifoldWalks").value += stats_.walks;
    counter(counters, "manifoldWalksConverged").value += stats_.converged;
    counter(counters, "manifoldNewtonIterations").value += stats_.iterations;
    counter(counters, "manifoldChainVertices").value += stats_.chainVertices;
    ChainCounter &max = counter(counters, "manifoldChainVerticesMax", ChainCounter::Merge::Max);
    max.value = std::max(max.value, stats_.maxChainVertices);
    counter(counters, "manifoldReverseWalks").value += stats_.reverseWalks;
    counter(counters, "manifoldNonReversible").value += stats_.nonReversible;
    counter(counters, "manifoldGlossySpecular").value += stats_.glossySpecular;
    counter(counters, "manifoldMediumVertices").value += stats_.mediumVertices;
    counter(counters, "manifoldCrossingWalks").value += stats_.crossingWalks;
}

}  // namespace pf
