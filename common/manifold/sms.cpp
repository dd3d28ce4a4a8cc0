#include "manifold/sms.h"

#include <cmath>
#include <vector>

#include "bsdf/bsdf.h"
#include "manifold/block_tridiagonal.h"
#include "manifold/generalized_geometry.h"
#include "manifold/specular_constraint.h"
#include "scene/scene.h"
#include "scene/shape.h"

namespace pf {

namespace {

// The post-check's tolerance on the angle between the ideal scattered direction and the direction to x_3:
// generous against the solver's residual (1e-5 by default), tiny against the O(1) error of a wrong root.
constexpr double kPostCheckCos = 1.0 - 1e-6;

// The caster vertex at `its` in the chain x_1 -> x_2 -> x_3: the event and eta_o / eta_i of §6.1, where
// eta_i is the index on x_1's side (the BSDF's eta() is interior over exterior, the exterior being the side
// the geometric normal points to).
std::optional<ManifoldVertex> casterVertex(const Intersection &its, const Vec3 &x1, Scattering event) {
    double eta = 1.0;
    if (event == Scattering::Refraction) {
        const double ratio = its.bsdf()->eta();
        eta = dot(x1 - its.p, its.n) > 0 ? ratio : 1.0 / ratio;
    }
    std::optional<ManifoldVertex> v = ManifoldVertex::surface(its, event, eta);
    if (v) v->predecessorAbove = dot(x1 - its.p, its.n) > 0;
    return v;
}

// The first surface seen from `from` through the point `target`. The ray leaves from the offset origin and aims at
// the target itself, so that a target on the surface is hit where it is (aiming from from.p would shift every
// reprojection by the offset, and Newton would stall at that distance from the root).
std::optional<Intersection> traceThrough(const Scene &scene, const Intersection &from, const Vec3 &target) {
    Ray ray = scene.spawnRay(from, target - from.p);
    const Vec3 d = target - ray.o;
    if (!(d.lengthSquared() > 0)) return std::nullopt;
    ray.d = normalize(d);
    Intersection its;
    if (!scene.intersect(ray, its)) return std::nullopt;
    return its;
}

// The next vertex of a chain: the first surface seen from `from` through `target`, which must be `caster` for the
// first vertex (the estimate is a sum over the solutions on it) and any ideally specular surface for the others
// (which of those count is the caller's contribution's business).
std::optional<Intersection> chainVertex(const Scene &scene, const Intersection &from, const Vec3 &target,
                                        const Shape *caster) {
    std::optional<Intersection> its = traceThrough(scene, from, target);
    if (!its || (caster ? its->shape != caster : specularEvent(*its->shape) == Scattering::None)) return std::nullopt;
    return its;
}

// Reprojection of the chain's proposed positions by tracing ([SMS §4.2]; for chains [SMS §5.6]): from x_1
// through the first target, then from each hit through the next target.
std::optional<SpecularChain> reproject(const Scene &scene, const Intersection &x1, const std::vector<Vec3> &targets,
                                       const Shape &caster) {
    SpecularChain chain;
    for (const Vec3 &target : targets) {
        const std::optional<Intersection> its =
            chainVertex(scene, chain.empty() ? x1 : chain.back(), target, chain.empty() ? &caster : nullptr);
        if (!its) return std::nullopt;
        chain.push_back(*its);
    }
    return chain;
}

// The seed chain ([SMS §4.7]): the first vertex is the uniform seed point on the caster (seen from x_1), each
// further one the first surface along the ideal specular direction out of the previous vertex. Sampling every
// vertex independently would add dimensions to the space of initial paths that Newton's basins then rarely
// cover ([SMS §5.6]); the traced seed follows the light as the first vertex's event sends it, and is exact for
// the chain through parallel flat interfaces and close to the solution for smooth closed casters such as a sphere.
std::optional<SpecularChain> seedChain(const Scene &scene, const Intersection &x1, const Vec3 &seed,
                                       const Shape &caster, int vertices) {
    std::optional<SpecularChain> chain = reproject(scene, x1, {seed}, caster);
    while (chain && static_cast<int>(chain->size()) < vertices) {
        const Intersection &last = chain->back();
        const Vec3 from = chain->size() == 1 ? x1.p : (*chain)[chain->size() - 2].p;
        const std::optional<ManifoldVertex> v = casterVertex(last, from, specularEvent(*last.shape));
        if (!v) return std::nullopt;
        const std::optional<Vec3> d = scatterAbout(normalize(from - v->p), v->n, v->scattering, v->eta);
        if (!d) return std::nullopt;
        const std::optional<Intersection> next = chainVertex(scene, last, last.p + *d, nullptr);
        if (!next) return std::nullopt;
        chain->push_back(*next);
    }
    return chain;
}

// The post-check: the converged vertex is the wanted event, not a back-facing or reflected root.
bool isWantedEvent(const ManifoldVertex &v, const Vec3 &x1, const Vec3 &x3) {
    const bool side1 = dot(x1 - v.p, v.ng) > 0, side3 = dot(x3 - v.p, v.ng) > 0;
    if ((side1 == side3) != (v.scattering == Scattering::Reflection)) return false;
    const std::optional<Vec3> s = scatterAbout(normalize(x1 - v.p), v.n, v.scattering, v.eta);
    return s && dot(*s, normalize(x3 - v.p)) > kPostCheckCos;
}

// The first vertex decides the chain: each further one is the first surface along the ideal direction.
bool sameSolution(const SpecularChain &a, const SpecularChain &b, const Vec3 &x1, double threshold) {
    return std::abs(dot(normalize(a.front().p - x1), normalize(b.front().p - x1)) - 1.0) < threshold;
}

}  // namespace

void SmsStatistics::reset() {
    for (auto *c : {&estimates, &solves, &successes, &bernoulli, &solutionsUsed, &guardHits, &maxTrials}) c->store(0);
}

double SmsStatistics::successRate() const {
    return solves ? static_cast<double>(successes) / static_cast<double>(solves) : 0.0;
}

double SmsStatistics::meanTrials() const {
    return solutionsUsed ? static_cast<double>(bernoulli) / static_cast<double>(solutionsUsed) : 0.0;
}

Scattering specularEvent(const Shape &caster) {
    const BSDF *bsdf = caster.bsdf();
    if (!bsdf) return Scattering::None;
    const uint32_t flags = bsdf->flags();
    if ((flags & (BSDFFlags::Smooth | BSDFFlags::Null)) != 0) return Scattering::None;
    if (flags & BSDFFlags::DeltaTransmission) return Scattering::Refraction;
    return (flags & BSDFFlags::DeltaReflection) ? Scattering::Reflection : Scattering::None;
}

std::optional<SpecularChain> solveSpecularChain(const Scene &scene, const Intersection &x1, const Vec3 &x3,
                                                const Shape &caster, int vertices, const SmsSettings &settings,
                                                Sampler &sampler) {
    PositionSample seed;
    caster.samplePosition(seed, sampler.next2D());
    if (specularEvent(caster) == Scattering::None) return std::nullopt;
    std::optional<SpecularChain> chain = seedChain(scene, x1, seed.p, caster, vertices);
    const size_t n = static_cast<size_t>(vertices);
    double beta = 1.0;
    std::vector<ManifoldVertex> v(n);
    std::vector<Vec2> step(n);
    BlockTridiagonal a(n);
    for (int i = 0; chain && i < settings.maxIterations; ++i) {
        a.resize(n);
        double residual2 = 0;
        for (size_t k = 0; k < n; ++k) {
            const std::optional<ManifoldVertex> vk =
                casterVertex((*chain)[k], k == 0 ? x1.p : v[k - 1].p, specularEvent(*(*chain)[k].shape));
            if (!vk) return std::nullopt;
            v[k] = *vk;
        }
        for (size_t k = 0; k < n; ++k) {
            const ManifoldVertex prev = k == 0 ? ManifoldVertex::fixedPosition(x1.p) : v[k - 1];
            const ManifoldVertex next = k + 1 == n ? ManifoldVertex::fixedPosition(x3) : v[k + 1];
            const std::optional<ChainConstraint> c = chainConstraint(settings.constraint, prev, v[k], next);
            if (!c) return std::nullopt;
            step[k] = c->value;
            residual2 += c->value.x * c->value.x + c->value.y * c->value.y;
            a.diag(k) = c->self;
            if (k > 0) a.lower(k) = c->prev;
            if (k + 1 < n) a.upper(k) = c->next;
        }
        if (std::sqrt(residual2) < settings.solverThreshold) {
            for (size_t k = 0; k < n; ++k)
                if (!isWantedEvent(v[k], k == 0 ? x1.p : v[k - 1].p, k + 1 == n ? x3 : v[k + 1].p)) return std::nullopt;
            return chain;
        }
        if (!a.factorize()) return std::nullopt;
        a.solve(step);
        // Step control: a proposal whose reprojection leaves the chain's surfaces is retried with half the step.
        for (; i < settings.maxIterations; ++i) {
            std::vector<Vec3> targets(n);
            for (size_t k = 0; k < n; ++k) targets[k] = v[k].p - (v[k].dpdu * step[k].x + v[k].dpdv * step[k].y) * beta;
            std::optional<SpecularChain> next = reproject(scene, x1, targets, caster);
            if (next) {
                chain = std::move(next);
                beta = std::min(1.0, 2.0 * beta);
                break;
            }
            beta *= 0.5;
        }
    }
    return std::nullopt;
}

std::optional<Intersection> solveSpecularVertex(const Scene &scene, const Intersection &x1, const Vec3 &x3,
                                                const Shape &caster, const SmsSettings &settings, Sampler &sampler) {
    const std::optional<SpecularChain> chain = solveSpecularChain(scene, x1, x3, caster, 1, settings, sampler);
    if (!chain) return std::nullopt;
    return chain->front();
}

std::optional<double> specularChainGeometry(const Intersection &x1, const SpecularChain &chain,
                                            const ManifoldVertex &x3) {
    const std::optional<ManifoldVertex> first = ManifoldVertex::surface(x1);
    const double cos1 = chain.empty() ? 0.0 : std::abs(dot(x1.n, normalize(chain.front().p - x1.p)));
    if (!first || !(cos1 > 0)) return std::nullopt;
    std::vector<ManifoldVertex> vertices = {*first};
    double etaProduct = 1.0;  // η_3 / η_1: the product of the vertices' eta_o / eta_i
    for (const Intersection &its : chain) {
        const Scattering event = its.shape ? specularEvent(*its.shape) : Scattering::None;
        const std::optional<ManifoldVertex> v = casterVertex(its, vertices.back().p, event);
        if (event == Scattering::None || !v) return std::nullopt;
        vertices.push_back(*v);
        etaProduct *= v->eta;
    }
    vertices.push_back(x3);
    // G(x_1 -> x_2 -> … -> x_3) is in projected solid angle at x_1 (§6.3); the receiver's BSDF value carries
    // the (shading) cosine there. A point x_3 has no area: its chain is solved the other way round, G(x_3 -> …
    // -> x_1) is the solid angle at x_3 per unit area at x_1, and the étendue factor (η_3 / η_1)² of
    // generalized_geometry.h turns it into the x_1 -> x_3 form that the radiance-scaled BSDF weights of the
    // casters expect.
    if (x3.type == ManifoldVertexType::FixedPosition) {
        const std::optional<double> g = generalizedGeometry(reversedChain(vertices));
        if (!g) return std::nullopt;
        return *g * etaProduct * etaProduct / cos1;
    }
    const std::optional<double> g = generalizedGeometry(vertices);
    if (!g) return std::nullopt;
    return *g / cos1;
}

Spectrum manifoldSum(const Scene &scene, const Intersection &x1, const Vec3 &x3, const Shape &caster, int vertices,
                     const SmsSettings &settings, Sampler &sampler, SmsStatistics &stats,
                     const std::function<Spectrum(const SpecularChain &chain)> &f) {
    ++stats.estimates;
    const auto trial = [&]() {
        ++stats.solves;
        std::optional<SpecularChain> its = solveSpecularChain(scene, x1, x3, caster, vertices, settings, sampler);
        if (its) ++stats.successes;
        return its;
    };
    Spectrum sum;
    if (settings.biased) {
        std::vector<SpecularChain> found;
        for (int64_t m = 0; m < settings.trials; ++m) {
            const std::optional<SpecularChain> its = trial();
            if (!its) continue;
            bool known = false;
            for (const SpecularChain &other : found)
                known = known || sameSolution(*its, other, x1.p, settings.uniquenessThreshold);
            if (known) continue;
            found.push_back(*its);
            sum += f(*its);
        }
        return sum;
    }
    const std::optional<SpecularChain> first = trial();
    if (!first) return sum;
    const Spectrum value = f(*first);
    // A zero contribution needs no estimate of 1/p_k.
    if (value.isBlack()) return sum;
    ++stats.solutionsUsed;
    int64_t count = 0;
    for (;;) {
        ++count;
        const std::optional<SpecularChain> its = trial();
        if (its && sameSolution(*its, *first, x1.p, settings.uniquenessThreshold)) break;
        if (count >= settings.trials) {
            ++stats.guardHits;
            break;
        }
    }
    stats.bernoulli += static_cast<uint64_t>(count);
    for (uint64_t seen = stats.maxTrials.load(); seen < static_cast<uint64_t>(count);)
        stats.maxTrials.compare_exchange_weak(seen, static_cast<uint64_t>(count));
    return value * static_cast<double>(count);
}

}  // namespace pf
