#include "manifold/manifold_vertex.h"

#include "bsdf/bsdf.h"
#include "core/frame.h"
#include "manifold/specular_constraint.h"
#include "path/vertex.h"
#include "scene/shape.h"

namespace pf {

namespace {

// Gram-Schmidt on (dp/du, dp/dv): e1 = dp/du / |dp/du|, e2 = the rest of dp/dv, normalized. This is a 2x2
// upper-triangular change of chart coordinates, which §6.2 applies to dn/du and dn/dv too, so that the normal
// derivatives stay those of the same parameterization. Returns false when the partials have rank < 2.
bool orthonormalizeChart(ManifoldVertex &v, const Vec3 &dpdu, const Vec3 &dpdv, const Vec3 &dndu, const Vec3 &dndv) {
    const double lu = dpdu.length();
    if (!(lu > 0.0) || !std::isfinite(lu)) return false;
    const Vec3 e1 = dpdu / lu;
    const double proj = dot(dpdv, e1);
    const Vec3 w = dpdv - e1 * proj;
    const double lw = w.length();
    if (!(lw > 1e-9 * dpdv.length()) || !std::isfinite(lw)) return false;
    v.dpdu = e1;
    v.dpdv = w / lw;
    v.dndu = dndu / lu;
    v.dndv = (dndv - dndu * (proj / lu)) / lw;
    return true;
}

// A chart around normal n with constant normal: endpoints whose normal derivatives never enter ∇C.
void flatChart(ManifoldVertex &v, const Vec3 &n) {
    v.ng = v.n = n;
    coordinateSystem(n, v.dpdu, v.dpdv);
    v.dndu = v.dndv = Vec3(0.0);
}

}  // namespace

std::optional<ManifoldVertex> ManifoldVertex::surface(const Intersection &its, Scattering scattering, double eta) {
    ManifoldVertex v;
    v.type = ManifoldVertexType::Surface;
    v.p = its.p;
    v.its = its;
    if (its.normalDerivativesPending) its.shape->fillNormalDerivatives(v.its);
    v.scattering = scattering;
    v.eta = eta;
    v.ng = its.n;
    v.n = its.shFrame.n;
    if (!orthonormalizeChart(v, its.dpdu, its.dpdv, v.its.dndu, v.its.dndv)) {
        if (scattering != Scattering::None) return std::nullopt;
        flatChart(v, its.n);
        v.n = its.shFrame.n;
    }
    return v;
}

std::optional<ManifoldVertex> ManifoldVertex::constrained(const Intersection &its, const Vec3 &prev, const Vec3 &next,
                                                          bool ideal) {
    const bool prevAbove = dot(prev - its.p, its.n) > 0;
    const bool nextAbove = dot(next - its.p, its.n) > 0;
    const Scattering scattering = prevAbove == nextAbove ? Scattering::Reflection : Scattering::Refraction;
    double eta = 1.0;
    if (scattering == Scattering::Refraction) {
        // §6.1: eta_o / eta_i; the BSDF's eta() is interior over exterior, and the exterior is the side the
        // geometric normal points to.
        const BSDF *bsdf = its.bsdf();
        const double ratio = bsdf ? bsdf->eta() : 1.0;
        eta = prevAbove ? ratio : 1.0 / ratio;
    }
    std::optional<ManifoldVertex> v = surface(its, scattering, eta);
    if (!v) return std::nullopt;
    v->predecessorAbove = prevAbove;
    ManifoldVertex a = fixedPosition(prev), b = fixedPosition(next);
    const std::optional<Vec3> h = generalizedHalfVector(a, *v, b);
    if (!h) return std::nullopt;
    v->halfVectorAbove = dot(*h, v->n) > 0;
    if (!ideal) {
        v->glossy = true;
        const std::optional<Vec2> c = constraintValue(a, *v, b);
        if (!c) return std::nullopt;
        v->offset = *c;
    }
    return v;
}

ManifoldVertex ManifoldVertex::fixedPosition(const Vec3 &p) {
    ManifoldVertex v;
    v.type = ManifoldVertexType::FixedPosition;
    v.p = p;
    return v;
}

ManifoldVertex ManifoldVertex::fixedDirection(const Vec3 &p, const Vec3 &d) {
    ManifoldVertex v;
    v.type = ManifoldVertexType::FixedDirection;
    v.p = p;
    flatChart(v, d);
    return v;
}

std::optional<ManifoldVertex> ManifoldVertex::medium(const Vec3 &p, const Vec3 &prev, const Vec3 &next) {
    ManifoldVertex v;
    v.type = ManifoldVertexType::Medium;
    v.scattering = Scattering::Medium;
    v.glossy = true;
    v.p = p;
    v.segment = (p - prev).length();
    if (!(v.segment > 0.0) || !std::isfinite(v.segment) || !v.setIncoming((p - prev) / v.segment)) return std::nullopt;
    const std::optional<Vec2> c = constraintValue(fixedPosition(prev), v, fixedPosition(next));
    if (!c) return std::nullopt;
    v.offset = *c;
    v.halfVectorAbove = dot(next - p, v.n) > 0;
    return v;
}

bool ManifoldVertex::setIncoming(const Vec3 &w) {
    const std::optional<std::pair<Vec3, Vec3>> frame = mediumFrame(w);
    if (!frame) return false;
    n = ng = w;
    dpdu = frame->first;
    dpdv = frame->second;
    dndu = dndv = Vec3(0.0);
    return true;
}

std::optional<ManifoldVertex> ManifoldVertex::mediumEndpoint(const Vec3 &p, const Vec3 &toward) {
    const Vec3 d = toward - p;
    const double len = d.length();
    if (!(len > 0.0) || !std::isfinite(len)) return std::nullopt;
    ManifoldVertex v;
    v.type = ManifoldVertexType::MediumEndpoint;
    v.p = p;
    flatChart(v, d / len);
    return v;
}

std::optional<ManifoldVertex> ManifoldVertex::endpoint(const PathVertex &pv, const Vec3 &neighbour) {
    switch (pv.type) {
        case VertexType::Surface:
            return surface(pv.its);
        case VertexType::Medium:
            return mediumEndpoint(pv.position(), neighbour);
        case VertexType::EmitterNode:
        case VertexType::SensorNode: {
            if (pv.hasDeltaPosition()) return fixedPosition(pv.position());
            if (pv.hasDeltaDirection()) return fixedDirection(pv.position(), normalize(pv.ps.n));
            if (pv.ps.n.isZero()) return std::nullopt;
            ManifoldVertex v;
            v.type = ManifoldVertexType::Surface;
            v.p = pv.position();
            v.its = pv.its;
            flatChart(v, normalize(pv.ps.n));
            return v;
        }
        default:
            return std::nullopt;
    }
}

std::vector<ManifoldVertex> reversedChain(const std::vector<ManifoldVertex> &chain) {
    std::vector<ManifoldVertex> reversed(chain.rbegin(), chain.rend());
    for (size_t i = 0; i < reversed.size(); ++i) {
        ManifoldVertex &v = reversed[i];
        if (v.type == ManifoldVertexType::Medium && i > 0 && i + 1 < reversed.size()) {
            if (const std::optional<ManifoldVertex> m =
                    ManifoldVertex::medium(v.p, reversed[i - 1].p, reversed[i + 1].p))
                v = *m;
            continue;
        }
        if (v.scattering != Scattering::Refraction) continue;
        v.eta = 1.0 / v.eta;
        v.predecessorAbove = !v.predecessorAbove;
    }
    return reversed;
}

std::optional<ManifoldVertex> virtualPlane(const Vec3 &p, const Vec3 &n, const Vec3 &pTarget, const Vec3 &nTarget) {
    const Vec3 n2 = dot(n, nTarget) < 0 ? -nTarget : nTarget;
    const Vec3 sum = n + n2;
    const double sumLength = sum.length();
    if (!(sumLength > 1e-12) || !std::isfinite(sumLength)) return std::nullopt;
    Vec3 normal = sum / sumLength;
    const Vec3 delta = pTarget - p;
    const double dist = delta.length();
    if (dist > 0.0) {
        const Vec3 d = delta / dist;
        const Vec3 w = normal - d * dot(normal, d);
        const double wl = w.length();
        if (!(wl > 1e-12) || !std::isfinite(wl)) return std::nullopt;
        normal = w / wl;
    }
    ManifoldVertex v;
    v.type = ManifoldVertexType::VirtualPlane;
    v.p = p;
    flatChart(v, normal);
    return v;
}

}  // namespace pf
