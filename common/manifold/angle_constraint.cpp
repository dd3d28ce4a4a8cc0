#include "manifold/angle_constraint.h"

#include <algorithm>
#include <cmath>

#include "manifold/specular_constraint.h"

namespace pf {

namespace {

// A value with its two partial derivatives with respect to the chart coordinates (u, v): forward-mode
// automatic differentiation, exact to rounding for the first-order vertex model of §6.2.
struct Dual {
    double v = 0, du = 0, dv = 0;
    Dual() = default;
    Dual(double value, double dU = 0, double dV = 0) : v(value), du(dU), dv(dV) {}
    Dual operator+(const Dual &o) const { return {v + o.v, du + o.du, dv + o.dv}; }
    Dual operator-(const Dual &o) const { return {v - o.v, du - o.du, dv - o.dv}; }
    Dual operator-() const { return {-v, -du, -dv}; }
    Dual operator*(const Dual &o) const { return {v * o.v, du * o.v + v * o.du, dv * o.v + v * o.dv}; }
    Dual operator/(const Dual &o) const {
        const double r = 1.0 / o.v;
        return {v * r, (du - v * r * o.du) * r, (dv - v * r * o.dv) * r};
    }
    // f(x) with f'(x) = slope.
    Dual chain(double value, double slope) const { return {value, du * slope, dv * slope}; }
};

Dual sqrt(const Dual &x) {
    const double s = std::sqrt(x.v);
    return x.chain(s, 0.5 / s);
}

struct DVec {
    Dual x, y, z;
    DVec operator+(const DVec &o) const { return {x + o.x, y + o.y, z + o.z}; }
    DVec operator-(const DVec &o) const { return {x - o.x, y - o.y, z - o.z}; }
    DVec operator-() const { return {-x, -y, -z}; }
    DVec operator*(const Dual &s) const { return {x * s, y * s, z * s}; }
};

Dual dot(const DVec &a, const DVec &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Dual dot(const DVec &a, const Vec3 &b) { return a.x * Dual(b.x) + a.y * Dual(b.y) + a.z * Dual(b.z); }
DVec normalize(const DVec &a) { return a * (Dual(1.0) / sqrt(dot(a, a))); }

// p + u du + v dv at u = v = 0.
DVec linear(const Vec3 &p, const Vec3 &du, const Vec3 &dv) {
    return {{p.x, du.x, dv.x}, {p.y, du.y, dv.y}, {p.z, du.z, dv.z}};
}
DVec constant(const Vec3 &p) { return linear(p, Vec3(0.0), Vec3(0.0)); }

// The ideal scattered direction of unit w about unit m (the same conventions as scatterAbout() in
// specular_constraint.h: w points away from the surface, eta = eta_o / eta_i, so that w + eta S ∥ m).
std::optional<DVec> scatter(const DVec &w, DVec m, Scattering scattering, double eta) {
    Dual c = dot(w, m);
    if (scattering == Scattering::Reflection) return m * (c * Dual(2.0)) - w;
    if (c.v < 0) {
        m = -m;
        c = -c;
    }
    const Dual invEta(1.0 / eta);
    const Dual sin2 = (Dual(1.0) - c * c) * invEta * invEta;
    if (!(sin2.v < 1.0)) return std::nullopt;  // total internal reflection
    const Dual cosT = sqrt(Dual(1.0) - sin2);
    return -w * invEta + m * (c * invEta - cosT);
}

// Spherical angles (θ = acos z, φ = atan2(y, x)) of unit w in `frame`.
void sphericalAngles(const DVec &w, const Frame &frame, Dual &theta, Dual &phi) {
    const Dual x = dot(w, frame.s), y = dot(w, frame.t), z = dot(w, frame.n);
    const double zc = std::clamp(z.v, -1.0, 1.0);
    theta = z.chain(std::acos(zc), -1.0 / std::sqrt(std::max(1e-300, 1.0 - zc * zc)));
    const double r2 = x.v * x.v + y.v * y.v;
    phi = Dual(std::atan2(y.v, x.v), (x.v * y.du - y.v * x.du) / r2, (x.v * y.dv - y.v * x.dv) / r2);
}

// The frame that puts `d` on its equator at φ = 0 (away from the poles and from the wrap of φ).
Frame equatorFrame(const Vec3 &d) {
    Vec3 a, b;
    coordinateSystem(d, a, b);
    return Frame(d, a, b);
}

// C at the vertex x (shading normal n) between a and b, each given with its derivatives with respect to the
// chart of the one point that moves, with v's event and eta; `frame` as in angleDifferenceConstraint().
std::optional<ConstraintJet> angleDifference(const DVec &a, const DVec &x, const DVec &n, const DVec &b,
                                             const ManifoldVertex &v, const Frame *frame) {
    const DVec toA = a - x, toB = b - x;
    if (!(dot(toA, toA).v > 0) || !(dot(toB, toB).v > 0)) return std::nullopt;
    DVec wi = normalize(toA), wo = normalize(toB);
    double eta = v.eta;
    std::optional<DVec> s = scatter(wi, n, v.scattering, eta);
    if (!s) {
        // Total internal reflection of ω_i: the reverse direction always refracts ([SMS §4.3]).
        std::swap(wi, wo);
        eta = 1.0 / eta;
        s = scatter(wi, n, v.scattering, eta);
        if (!s) return std::nullopt;
    }
    const Frame local = frame ? *frame : equatorFrame(Vec3(wo.x.v, wo.y.v, wo.z.v));
    Dual thetaS, phiS, thetaO, phiO;
    sphericalAngles(*s, local, thetaS, phiS);
    sphericalAngles(wo, local, thetaO, phiO);
    const Dual dTheta = thetaS - thetaO;
    Dual dPhi = phiS - phiO;
    // Δφ wrapped into [-π, π] ([SMS eq. 12]; the reference code's 2020 results lack this wrap).
    if (dPhi.v > kPi) dPhi.v -= 2 * kPi;
    if (dPhi.v < -kPi) dPhi.v += 2 * kPi;
    ConstraintJet jet;
    jet.value = Vec2(dTheta.v, dPhi.v);
    jet.derivative = Mat2(dTheta.du, dTheta.dv, dPhi.du, dPhi.dv);
    if (!std::isfinite(jet.derivative.frobeniusNormSquared())) return std::nullopt;
    return jet;
}

DVec chartOf(const ManifoldVertex &v) { return linear(v.p, v.dpdu, v.dpdv); }

}  // namespace

std::optional<ConstraintJet> angleDifferenceConstraint(const Vec3 &a, const ManifoldVertex &v, const Vec3 &b,
                                                       const Frame *frame) {
    return angleDifference(constant(a), chartOf(v), normalize(linear(v.n, v.dndu, v.dndv)), constant(b), v, frame);
}

std::optional<ChainConstraint> chainConstraint(SmsConstraint form, const ManifoldVertex &prev, const ManifoldVertex &v,
                                               const ManifoldVertex &next, const Frame *frame) {
    ChainConstraint c;
    if (form == SmsConstraint::HalfVector) {
        const std::optional<Vec2> value = constraintValue(prev, v, next);
        const std::optional<ConstraintDerivatives> d = constraintDerivatives(prev, v, next);
        if (!value || !d) return std::nullopt;
        c.value = *value - v.offset;
        c.prev = d->prev;
        c.self = d->self;
        c.next = d->next;
        return c;
    }
    // Three passes of the dual numbers, one per moving vertex: the same value, one block each.
    const DVec a = constant(prev.p), x = constant(v.p), b = constant(next.p);
    const DVec n = constant(normalize(v.n));
    const std::optional<ConstraintJet> self = angleDifferenceConstraint(prev.p, v, next.p, frame);
    const std::optional<ConstraintJet> wrtPrev = angleDifference(chartOf(prev), x, n, b, v, frame);
    const std::optional<ConstraintJet> wrtNext = angleDifference(a, x, n, chartOf(next), v, frame);
    if (!self || !wrtPrev || !wrtNext) return std::nullopt;
    c.value = self->value;
    c.self = self->derivative;
    c.prev = wrtPrev->derivative;
    c.next = wrtNext->derivative;
    return c;
}

std::optional<ConstraintJet> halfVectorConstraint(const Vec3 &a, const ManifoldVertex &v, const Vec3 &b) {
    const ManifoldVertex prev = ManifoldVertex::fixedPosition(a), next = ManifoldVertex::fixedPosition(b);
    const std::optional<Vec2> c = constraintValue(prev, v, next);
    const std::optional<ConstraintDerivatives> d = constraintDerivatives(prev, v, next);
    if (!c || !d) return std::nullopt;
    return ConstraintJet{*c - v.offset, d->self};
}

}  // namespace pf
