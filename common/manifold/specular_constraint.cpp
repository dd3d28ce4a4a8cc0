#include "manifold/specular_constraint.h"

namespace pf {

namespace {

// The fixed direction a whose projection spans the continuous frame of glossy vertices (header). A continuous
// tangent field on a closed surface must vanish somewhere, so the frame has poles, at n = ±a; this a keeps them
// as far as possible (54.7 degrees) from the six axis directions, the normals of axis-aligned planes and of the
// tops, bottoms and sides of shapes in scenes built with a y or z up axis.
const Vec3 kFrameDirection = Vec3(1.0, 1.0, 1.0) / std::sqrt(3.0);

// The tangent frame T = [s t] of a constrained Surface vertex (header) and its derivatives along the chart
// coordinates u and v, under the first-order vertex model n(u, v) = n + u dn/du + v dn/dv (§6.2).
struct TangentFrame {
    Vec3 s, t;
    Vec3 ds[2], dt[2];  // ∂s/∂u, ∂s/∂v and ∂t/∂u, ∂t/∂v
};

// The projection a - <a, n> n of a fixed vector a onto the shading tangent plane, and its derivatives
// -<a, ∂n> n - <a, n> ∂n ([TR A2]'s tangent-frame derivatives, §6.2).
void projectedTangent(const ManifoldVertex &v, const Vec3 &a, Vec3 &s, Vec3 ds[2]) {
    const double an = dot(a, v.n);
    s = a - v.n * an;
    ds[0] = v.n * -dot(a, v.dndu) - v.dndu * an;
    ds[1] = v.n * -dot(a, v.dndv) - v.dndv * an;
}

std::optional<TangentFrame> tangentFrame(const ManifoldVertex &v) {
    TangentFrame f;
    if (!v.glossy) {
        // [TR A2]: the chart's partials projected onto the shading tangent plane, not normalized. The chart
        // vectors are held fixed, which is exact on planes and mesh triangles.
        projectedTangent(v, v.dpdu, f.s, f.ds);
        projectedTangent(v, v.dpdv, f.t, f.dt);
        return f;
    }
    // ŝ = γ(a - <a, n> n), t = n × ŝ: a function of the shading normal alone, so continuous wherever n is,
    // and differentiated exactly through ∂γ(z) = (I - ẑ ẑ^T) ∂z / |z|.
    Vec3 s0, ds0[2];
    projectedTangent(v, kFrameDirection, s0, ds0);
    const double length = s0.length();
    if (!(length > 1e-9) || !std::isfinite(length)) return std::nullopt;
    f.s = s0 / length;
    f.t = cross(v.n, f.s);
    const Vec3 dn[2] = {v.dndu, v.dndv};
    for (int k = 0; k < 2; ++k) {
        f.ds[k] = (ds0[k] - f.s * dot(f.s, ds0[k])) / length;
        f.dt[k] = cross(dn[k], f.s) + cross(v.n, f.ds[k]);
    }
    return f;
}

// Unit direction from `from` to `to` and the inverse distance; false for coincident points.
bool unitDirection(const Vec3 &from, const Vec3 &to, Vec3 &dir, double &invLength) {
    const Vec3 d = to - from;
    const double len = d.length();
    if (!(len > 0.0) || !std::isfinite(len)) return false;
    invLength = 1.0 / len;
    dir = d * invLength;
    return true;
}

// Projects out the component along the unit vector h: (I - h h^T) x, the derivative of a normalization.
Vec3 projectOut(const Vec3 &x, const Vec3 &h) { return x - h * dot(x, h); }

// The block [<dH/du, s> <dH/dv, s>; <dH/du, t> <dH/dv, t>].
Mat2 frameBlock(const Vec3 &dHdu, const Vec3 &dHdv, const Vec3 &s, const Vec3 &t) {
    return {dot(dHdu, s), dot(dHdv, s), dot(dHdu, t), dot(dHdv, t)};
}

// Derivatives of a unit direction ω = γ(q - x) w.r.t. the chart of q (scale = +1/|q - x|) or of x
// (scale = -1/|q - x|), projected onto the frame [s t] after the normalization of h (projection along h).
Mat2 neighbourBlock(const ManifoldVertex &q, const Vec3 &w, double scale, const Vec3 &h, const Vec3 &s, const Vec3 &t) {
    const Vec3 du = projectOut(projectOut(q.dpdu, w) * scale, h);
    const Vec3 dv = projectOut(projectOut(q.dpdv, w) * scale, h);
    return frameBlock(du, dv, s, t);
}

std::optional<ConstraintDerivatives> fixedDirectionDerivatives(const ManifoldVertex &v, const ManifoldVertex &next) {
    Vec3 w;
    double il;
    if (!unitDirection(v.p, next.p, w, il)) return std::nullopt;
    // c = T^T ω with T = [dp/du dp/dv] constant (the chart ⟂ d); ω's normalization contributes (I - ω ω^T).
    // No second normalization: pass h = 0 so that projectOut(·, h) is the identity.
    ConstraintDerivatives d;
    d.self = neighbourBlock(v, w, -il, Vec3(0.0), v.dpdu, v.dpdv);
    d.next = neighbourBlock(next, w, il, Vec3(0.0), v.dpdu, v.dpdv);
    return d;
}

}  // namespace

std::optional<Vec3> generalizedHalfVector(const ManifoldVertex &prev, const ManifoldVertex &v,
                                          const ManifoldVertex &next) {
    Vec3 wi, wo;
    double ili, ilo;
    if (!unitDirection(v.p, prev.p, wi, ili) || !unitDirection(v.p, next.p, wo, ilo)) return std::nullopt;
    const Vec3 h = wi + wo * v.eta;
    const double len = h.length();
    if (!(len > 1e-12) || !std::isfinite(len)) return std::nullopt;
    return h / len;
}

std::optional<Vec2> constraintValue(const ManifoldVertex &prev, const ManifoldVertex &v, const ManifoldVertex &next) {
    if (v.type == ManifoldVertexType::FixedDirection) {
        Vec3 w;
        double il;
        if (!unitDirection(v.p, next.p, w, il)) return std::nullopt;
        return Vec2(dot(v.dpdu, w), dot(v.dpdv, w));
    }
    const std::optional<Vec3> h = generalizedHalfVector(prev, v, next);
    const std::optional<TangentFrame> f = tangentFrame(v);
    if (!h || !f) return std::nullopt;
    return Vec2(dot(*h, f->s), dot(*h, f->t));
}

// A port of computeDerivatives of [TR A2] (not the thesis listing, whose diagonal (0,1) entry has the dpdv/dndv
// typo, ALGORITHMS.md §6.2). h = γ(z), z = ω_i + eta ω_o; ∂h = (I - h h^T) ∂z / |z| (§6.2), and the tangent
// frame's own derivatives enter the diagonal block only.
std::optional<ConstraintDerivatives> constraintDerivatives(const ManifoldVertex &prev, const ManifoldVertex &v,
                                                           const ManifoldVertex &next) {
    if (v.type == ManifoldVertexType::FixedDirection) return fixedDirectionDerivatives(v, next);
    Vec3 wi, wo;
    double ili, ilo;
    if (!unitDirection(v.p, prev.p, wi, ili) || !unitDirection(v.p, next.p, wo, ilo)) return std::nullopt;
    Vec3 h = wi + wo * v.eta;
    const double hl = h.length();
    if (!(hl > 1e-12) || !std::isfinite(hl)) return std::nullopt;
    const double ilh = 1.0 / hl;
    h *= ilh;
    const std::optional<TangentFrame> f = tangentFrame(v);
    if (!f) return std::nullopt;
    const Vec3 &s = f->s, &t = f->t;
    // Scale factors of ∂ω_i and eta ∂ω_o, including the 1/|z| of h's normalization.
    const double si = ili * ilh, so = ilo * v.eta * ilh;

    ConstraintDerivatives d;
    d.prev = neighbourBlock(prev, wi, si, h, s, t);
    d.next = neighbourBlock(next, wo, so, h, s, t);

    // Moving x_i moves both directions: ∂ω_i/∂u = -(I - ω_i ω_i^T) dp/du / |x_{i-1} - x_i|, likewise ω_o.
    const Vec3 dHdu = projectOut(v.dpdu * -(si + so) + wi * (dot(wi, v.dpdu) * si) + wo * (dot(wo, v.dpdu) * so), h);
    const Vec3 dHdv = projectOut(v.dpdv * -(si + so) + wi * (dot(wi, v.dpdv) * si) + wo * (dot(wo, v.dpdv) * so), h);
    // Plus the frame's derivatives with h fixed (tangentFrame()).
    d.self =
        frameBlock(dHdu, dHdv, s, t) + Mat2(dot(f->ds[0], h), dot(f->ds[1], h), dot(f->dt[0], h), dot(f->dt[1], h));
    return d;
}

std::optional<Vec3> microfacetNormal(const ManifoldVertex &v) {
    const std::optional<TangentFrame> f = tangentFrame(v);
    if (!f) return std::nullopt;
    const Vec3 &s = f->s, &t = f->t;
    // The tangential part of m is a s + b t with <m, s> = o_x and <m, t> = o_y: a 2x2 Gram system.
    const Mat2 gram(dot(s, s), dot(s, t), dot(s, t), dot(t, t));
    Mat2 inv;
    if (!gram.invert(inv)) return std::nullopt;
    const Vec2 ab = inv * v.offset;
    const Vec3 tangential = s * ab.x + t * ab.y;
    const double t2 = tangential.lengthSquared();
    if (!(t2 < 1.0)) return std::nullopt;
    const double normal = std::sqrt(1.0 - t2);
    return tangential + v.n * (v.halfVectorAbove ? normal : -normal);
}

std::optional<Vec3> scatterAbout(const Vec3 &wi, const Vec3 &m, Scattering scattering, double eta) {
    const double c = dot(wi, m);
    if (scattering == Scattering::Reflection) return m * (2.0 * c) - wi;
    // Snell's law about m oriented towards wi: the tangential part of ω_o is -ω_i's over eta, so that
    // ω_i + eta ω_o is parallel to m.
    const Vec3 mf = c >= 0 ? m : -m;
    const double cosI = std::abs(c);
    const double sin2T = (1.0 - cosI * cosI) / (eta * eta);
    if (!(sin2T < 1.0)) return std::nullopt;
    const double cosT = std::sqrt(1.0 - sin2T);
    return wi * (-1.0 / eta) + mf * (cosI / eta - cosT);
}

}  // namespace pf
