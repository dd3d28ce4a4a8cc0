#include "path/manifold_perturbation.h"

#include <algorithm>
#include <optional>

#include "manifold/generalized_geometry.h"
#include "path/perturbation.h"
#include "scene/scene.h"

namespace pf {

namespace {

// How far (relative to the scene scale) the second chain traced from x_f may land from the moving vertex
// found by the walk before the proposal is dropped: the walk converges to 1e-7 of it.
constexpr double kLandingTolerance = 1e-5;
// How close, relative to the length of x_f's edge, the reverse walk's first vertex must come back to x's
// (Mitsuba compares the first walked vertex with a relative tolerance, §6.5).
constexpr double kReverseTolerance = 1e-4;

TransportMode walkMode(int dir) { return dir > 0 ? TransportMode::Importance : TransportMode::Radiance; }

// The next non-specular vertex from `from` in direction dir, or -1 past the end of the path.
int nextNonSpecular(const PathView &x, int from, int dir) {
    for (int j = from + dir; j >= 0 && j < x.length(); j += dir)
        if (isNonSpecular(x.vertex(j))) return j;
    return -1;
}

// Endpoint nodes a strategy can use: a position on a shape, or a point (the environment has neither).
bool usableEnd(const PathVertex &v) {
    return v.type != VertexType::EmitterNode || v.its.shape != nullptr || v.hasDeltaPosition();
}

// The chain x_from .. x_to of path p for WalkManifold and the generalized geometry term: non-specular ends
// and ideal specular vertices in between, in order from `from`.
std::optional<std::vector<ManifoldVertex>> manifoldChain(const PathView &p, int from, int to) {
    const int dir = to > from ? 1 : -1;
    std::vector<ManifoldVertex> chain;
    const auto first = ManifoldVertex::endpoint(p.vertex(from), p.vertex(from + dir).position());
    if (!first) return std::nullopt;
    chain.push_back(*first);
    for (int i = from + dir; i != to; i += dir) {
        const auto v = ManifoldVertex::constrained(p.vertex(i).its, p.vertex(i - dir).position(),
                                                   p.vertex(i + dir).position(), true);
        if (!v) return std::nullopt;
        chain.push_back(*v);
    }
    const auto last = ManifoldVertex::endpoint(p.vertex(to), p.vertex(to - dir).position());
    if (!last) return std::nullopt;
    chain.push_back(*last);
    return chain;
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

// The direction of the ray from `from` through point p, as rayDirection() measures it.
Vec3 rayDirectionTo(const Scene &scene, const PathVertex &from, const Vec3 &p) {
    PathVertex to;
    to.its.p = p;
    return rayDirection(scene, from, to);
}

}  // namespace

ManifoldPerturbation::ManifoldPerturbation(const Scene &scene, double lambda) : lambda_(lambda), walk_(scene) {}

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

std::vector<ManifoldPerturbation::Strategy> ManifoldPerturbation::strategies(const PathView &x) {
    std::vector<Strategy> list;
    for (int s = 0; s < x.length(); ++s) {
        if (!isNonSpecular(x.vertex(s)) || !usableEnd(x.vertex(s))) continue;
        for (const int dir : {1, -1}) {
            const int m = nextNonSpecular(x, s, dir);
            if (m < 0 || x.vertex(m).type != VertexType::Surface) continue;
            const int f = nextNonSpecular(x, m, dir);
            if (f < 0 || !usableEnd(x.vertex(f))) continue;
            list.push_back({s, m, f});
        }
    }
    return list;
}

bool ManifoldPerturbation::applies(const PathView &x) const { return !strategies(x).empty(); }

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
    const std::vector<Strategy> list = strategies(x);
    if (list.empty()) return false;
    const size_t pick = std::min(list.size() - 1, static_cast<size_t>(sampler.next1D() * list.size()));
    const Strategy st = list[pick];
    record = {std::min(st.source, st.fixed), std::max(st.source, st.fixed), std::abs(st.fixed - st.source) - 1,
              st.source};
    const int dir = st.moving > st.source ? 1 : -1;
    const Vec3 mean = rayDirection(scene, x.vertex(st.source), x.vertex(st.source + dir));
    const Vec3 d = kernel(scene, x, st.source, dir).sample(mean, sampler.next2D());
    y = x;
    if (!aimSensor(scene, y.vertex(st.source), d)) return false;
    if (!propagate(scene, sampler, walkMode(dir), x, y, st.source, st.moving, d)) return false;
    if (std::abs(st.fixed - st.moving) == 1) return connectJunction(scene, y, std::min(st.moving, st.fixed));
    return connectChain(scene, sampler, x, y, st);
}

bool ManifoldPerturbation::connectChain(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                        const Strategy &st) const {
    // WalkManifold(x_f, ..., x_m -> x'_m): the fixed end plays x_1 (§6.4).
    const int dir = st.moving > st.fixed ? 1 : -1;
    const PathVertex &moved = y.vertex(st.moving);
    const auto chain = manifoldChain(x, st.fixed, st.moving);
    const auto target = ManifoldVertex::surface(moved.its);
    if (!chain || !target || !isNonSpecular(moved)) return false;
    const WalkResult walked = walk_.walk(*chain, *target);
    stats_.walks += 1;
    stats_.iterations += walked.stats.iterations;
    stats_.chainVertices += walked.stats.chainSize;
    stats_.maxChainVertices = std::max(stats_.maxChainVertices, static_cast<double>(walked.stats.chainSize));
    if (!walked.converged()) return false;
    stats_.converged += 1;

    // The path-space vertices of the new chain: traced from x_f through the walked chain's first vertex, each
    // specular vertex keeping its Dirac lobe, which must land on x'_m.
    MutablePath traced = y;
    PathVertex &fixed = traced.vertex(st.fixed);
    const Vec3 d = rayDirectionTo(scene, fixed, walked.chain[1].p);
    if (!aimSensor(scene, fixed, d) || !propagate(scene, sampler, walkMode(dir), x, traced, st.fixed, st.moving, d))
        return false;
    if ((traced.vertex(st.moving).position() - moved.position()).length() > kLandingTolerance * walk_.sceneScale())
        return false;
    y.vertex(st.fixed).ps.uv = fixed.ps.uv;
    for (int i = st.fixed + dir; i != st.moving; i += dir) y.vertex(i) = traced.vertex(i);
    for (int i = std::min(st.fixed, st.moving); i < std::max(st.fixed, st.moving); ++i) y.edge(i) = traced.edge(i);

    // The reverse walk must bring the chain back to x's (mandatory, §6.5).
    const auto back = manifoldChain(y, st.fixed, st.moving);
    const auto origin = ManifoldVertex::surface(x.vertex(st.moving).its);
    if (!back || !origin) return false;
    const WalkResult returned = walk_.walk(*back, *origin);
    stats_.reverseWalks += 1;
    const Vec3 &first = x.vertex(st.fixed + dir).position();
    const double scale = (first - x.vertex(st.fixed).position()).length();
    if (!returned.converged() || (returned.chain[1].p - first).length() > kReverseTolerance * scale) {
        stats_.nonReversible += 1;
        return false;
    }
    return true;
}

double ManifoldPerturbation::density(const Scene &scene, const PathView &x, const PathView &y,
                                     const MutationRecord &record) const {
    const int n = x.length();
    if (record.source < 0 || y.length() != n) return 0.0;
    const int source = record.source, fixed = source == record.l ? record.m : record.l;
    const std::vector<Strategy> list = strategies(x);
    const auto st = std::find_if(list.begin(), list.end(),
                                 [&](const Strategy &s) { return s.source == source && s.fixed == fixed; });
    if (st == list.end()) return 0.0;
    // y must have x's configuration over the range the move changed.
    for (int i = std::min(source, fixed); i <= std::max(source, fixed); ++i)
        if (isNonSpecular(x.vertex(i)) != isNonSpecular(y.vertex(i))) return 0.0;
    const int dir = st->moving > source ? 1 : -1;
    const TransportMode mode = walkMode(dir);
    double density = kernel(scene, x, source, dir)
                         .eval(rayDirection(scene, x.vertex(source), x.vertex(source + dir)),
                               rayDirection(scene, y.vertex(source), y.vertex(source + dir))) /
                     static_cast<double>(list.size());
    density *= propagationJacobian(y, source, st->moving, mode);
    if (mode == TransportMode::Importance)
        for (int i = source + 1; i < st->moving; ++i) density *= importanceToCanonical(scene, y, i);
    if (std::abs(fixed - st->moving) > 1) {
        const double rho = measureRatio(y, fixed, st->moving);
        density = rho > 0 ? density / rho : 0.0;
    }
    return density;
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
}

}  // namespace pf
