#include "manifold/sms.h"

#include <cmath>
#include <vector>

#include "bsdf/bsdf.h"
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

// The first surface seen from x1 through the point `target`, if it lies on `caster`. The ray leaves from x1's
// offset origin and aims at the target itself, so that a target on the caster is hit where it is (aiming from
// x1.p would shift every reprojection by the offset, and Newton would stall at that distance from the root).
std::optional<Intersection> traceToCaster(const Scene &scene, const Intersection &x1, const Vec3 &target,
                                          const Shape &caster) {
    Ray ray = scene.spawnRay(x1, target - x1.p);
    const Vec3 d = target - ray.o;
    if (!(d.lengthSquared() > 0)) return std::nullopt;
    ray.d = normalize(d);
    Intersection its;
    if (!scene.intersect(ray, its) || its.shape != &caster) return std::nullopt;
    return its;
}

// The post-check: the converged vertex is the wanted event, not a back-facing or reflected root.
bool isWantedEvent(const ManifoldVertex &v, const Vec3 &x1, const Vec3 &x3) {
    const bool side1 = dot(x1 - v.p, v.ng) > 0, side3 = dot(x3 - v.p, v.ng) > 0;
    if ((side1 == side3) != (v.scattering == Scattering::Reflection)) return false;
    const std::optional<Vec3> s = scatterAbout(normalize(x1 - v.p), v.n, v.scattering, v.eta);
    return s && dot(*s, normalize(x3 - v.p)) > kPostCheckCos;
}

bool sameSolution(const Intersection &a, const Intersection &b, const Vec3 &x1, double threshold) {
    return std::abs(dot(normalize(a.p - x1), normalize(b.p - x1)) - 1.0) < threshold;
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

std::optional<Intersection> solveSpecularVertex(const Scene &scene, const Intersection &x1, const Vec3 &x3,
                                                const Shape &caster, const SmsSettings &settings, Sampler &sampler) {
    const Scattering event = specularEvent(caster);
    PositionSample seed;
    caster.samplePosition(seed, sampler.next2D());
    if (event == Scattering::None) return std::nullopt;
    std::optional<Intersection> its = traceToCaster(scene, x1, seed.p, caster);
    double beta = 1.0;
    for (int i = 0; its && i < settings.maxIterations; ++i) {
        const std::optional<ManifoldVertex> v = casterVertex(*its, x1.p, event);
        if (!v) return std::nullopt;
        const std::optional<ConstraintJet> c = specularConstraint(settings.constraint, x1.p, *v, x3);
        if (!c) return std::nullopt;
        if (std::hypot(c->value.x, c->value.y) < settings.solverThreshold)
            return isWantedEvent(*v, x1.p, x3) ? its : std::nullopt;
        Mat2 inverse;
        if (!c->derivative.invert(inverse)) return std::nullopt;
        const Vec2 step = inverse * c->value;
        // Step control: a proposal whose reprojection misses the caster is retried with half the step.
        for (; i < settings.maxIterations; ++i) {
            const Vec3 target = v->p - (v->dpdu * step.x + v->dpdv * step.y) * beta;
            const std::optional<Intersection> next = traceToCaster(scene, x1, target, caster);
            if (next) {
                its = next;
                beta = std::min(1.0, 2.0 * beta);
                break;
            }
            beta *= 0.5;
        }
    }
    return std::nullopt;
}

std::optional<double> specularChainGeometry(const Intersection &x1, const Intersection &x2, const ManifoldVertex &x3) {
    const Scattering event = x2.shape ? specularEvent(*x2.shape) : Scattering::None;
    const std::optional<ManifoldVertex> first = ManifoldVertex::surface(x1);
    const std::optional<ManifoldVertex> caster = casterVertex(x2, x1.p, event);
    const double cos1 = std::abs(dot(x1.n, normalize(x2.p - x1.p)));
    if (event == Scattering::None || !first || !caster || !(cos1 > 0)) return std::nullopt;
    // G(x_1 -> x_2 -> x_3) is in projected solid angle at x_1 (§6.3); the receiver's BSDF value carries
    // the (shading) cosine there. A point x_3 has no area: its chain is solved the other way round, G(x_3 -> x_2
    // -> x_1) is the solid angle at x_3 per unit area at x_1, and the étendue factor (η_3 / η_1)² of
    // generalized_geometry.h (the caster's eta, eta_o / eta_i in chain order) turns it into the x_1 -> x_3
    // form that the radiance-scaled BSDF weights of the caster expect.
    if (x3.type == ManifoldVertexType::FixedPosition) {
        const std::optional<double> g = generalizedGeometry(reversedChain({*first, *caster, x3}));
        if (!g) return std::nullopt;
        return *g * caster->eta * caster->eta / cos1;
    }
    const std::optional<double> g = generalizedGeometry({*first, *caster, x3});
    if (!g) return std::nullopt;
    return *g / cos1;
}

Spectrum manifoldSum(const Scene &scene, const Intersection &x1, const Vec3 &x3, const Shape &caster,
                     const SmsSettings &settings, Sampler &sampler, SmsStatistics &stats,
                     const std::function<Spectrum(const Intersection &x2)> &f) {
    ++stats.estimates;
    const auto trial = [&]() {
        ++stats.solves;
        std::optional<Intersection> its = solveSpecularVertex(scene, x1, x3, caster, settings, sampler);
        if (its) ++stats.successes;
        return its;
    };
    Spectrum sum;
    if (settings.biased) {
        std::vector<Intersection> found;
        for (int64_t m = 0; m < settings.trials; ++m) {
            const std::optional<Intersection> its = trial();
            if (!its) continue;
            bool known = false;
            for (const Intersection &other : found)
                known = known || sameSolution(*its, other, x1.p, settings.uniquenessThreshold);
            if (known) continue;
            found.push_back(*its);
            sum += f(*its);
        }
        return sum;
    }
    const std::optional<Intersection> first = trial();
    if (!first) return sum;
    const Spectrum value = f(*first);
    // A zero contribution needs no estimate of 1/p_k.
    if (value.isBlack()) return sum;
    ++stats.solutionsUsed;
    int64_t count = 0;
    for (;;) {
        ++count;
        const std::optional<Intersection> its = trial();
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
