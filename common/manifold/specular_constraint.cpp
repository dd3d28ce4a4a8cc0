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

// Derivative of a unit direction ω = γ(q - x) when q moves along e (scale = +1/|q - x|) or x does
// (scale = -1/|q - x|), projected onto the frame [s t] after the normalization of h (projection along h).
Vec2 neighbourColumn(const Vec3 &e, const Vec3 &w, double scale, const Vec3 &h, const Vec3 &s, const Vec3 &t) {
    const Vec3 d = projectOut(projectOut(e, w) * scale, h);
    return {dot(d, s), dot(d, t)};
}

Mat2 fromColumns(const Vec2 &u, const Vec2 &v) { return {u.x, v.x, u.y, v.y}; }

// The same along both chart directions of q.
Mat2 neighbourBlock(const ManifoldVertex &q, const Vec3 &w, double scale, const Vec3 &h, const Vec3 &s, const Vec3 &t) {
    return fromColumns(neighbourColumn(q.dpdu, w, scale, h, s, t), neighbourColumn(q.dpdv, w, scale, h, s, t));
}

// The third coordinate of a medium vertex: its axis ω_in; zero for other vertices, which have two.
Vec2 neighbourAxis(const ManifoldVertex &q, const Vec3 &w, double scale, const Vec3 &h, const Vec3 &s, const Vec3 &t) {
    return q.type == ManifoldVertexType::Medium ? neighbourColumn(q.n, w, scale, h, s, t) : Vec2();
}

// The medium constraint's geometry (header): ω_in, ω_out, the inverse lengths and the frame.
struct MediumGeometry {
    Vec3 wIn, wOut, s, t;
    double ilIn = 0, ilOut = 0;
};

std::optional<MediumGeometry> mediumGeometry(const ManifoldVertex &prev, const ManifoldVertex &v,
                                             const ManifoldVertex &next) {
    MediumGeometry g;
    if (!unitDirection(prev.p, v.p, g.wIn, g.ilIn) || !unitDirection(v.p, next.p, g.wOut, g.ilOut)) return std::nullopt;
    const std::optional<std::pair<Vec3, Vec3>> f = mediumFrame(g.wIn);
    if (!f) return std::nullopt;
    g.s = f->first;
    g.t = f->second;
    return g;
}

// δc of a medium vertex when ω_in turns by dIn and ω_out by dOut: the frame turns with ω_in,
// δŝ = (I - ŝ ŝ^T) δ(a - <a, ω> ω) / |a - <a, ω> ω|, δt = δω × ŝ + ω × δŝ.
Vec2 mediumVariation(const MediumGeometry &g, const Vec3 &dIn, const Vec3 &dOut) {
    const double aw = dot(kFrameDirection, g.wIn);
    const double length = (kFrameDirection - g.wIn * aw).length();
    const Vec3 ds0 = g.wIn * -dot(kFrameDirection, dIn) - dIn * aw;
    const Vec3 ds = (ds0 - g.s * dot(g.s, ds0)) / length;
    const Vec3 dt = cross(dIn, g.s) + cross(g.wIn, ds);
    return {dot(ds, g.wOut) + dot(g.s, dOut), dot(dt, g.wOut) + dot(g.t, dOut)};
}

// ∂c of a medium vertex along displacement e of its predecessor (which = -1), itself (0) or its successor (+1).
Vec2 mediumColumn(const MediumGeometry &g, int which, const Vec3 &e) {
    const Vec3 dIn = projectOut(e, g.wIn) * (which == 0 ? g.ilIn : which < 0 ? -g.ilIn : 0.0);
    const Vec3 dOut = projectOut(e, g.wOut) * (which == 0 ? -g.ilOut : which > 0 ? g.ilOut : 0.0);
    return mediumVariation(g, dIn, dOut);
}

std::optional<ConstraintDerivatives> mediumDerivatives(const ManifoldVertex &prev, const ManifoldVertex &v,
                                                       const ManifoldVertex &next) {
    const std::optional<MediumGeometry> g = mediumGeometry(prev, v, next);
    if (!g) return std::nullopt;
    ConstraintDerivatives d;
    const auto block = [&](const ManifoldVertex &q, int which) {
        return fromColumns(mediumColumn(*g, which, q.dpdu), mediumColumn(*g, which, q.dpdv));
    };
    const auto axis = [&](const ManifoldVertex &q, int which) {
        return q.type == ManifoldVertexType::Medium ? mediumColumn(*g, which, q.n) : Vec2();
    };
    d.prev = block(prev, -1);
    d.self = block(v, 0);
    d.next = block(next, 1);
    d.prevAxis = axis(prev, -1);
    d.selfAxis = axis(v, 0);
    d.nextAxis = axis(next, 1);
    return d;
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
    d.nextAxis = neighbourAxis(next, w, il, Vec3(0.0), v.dpdu, v.dpdv);
    return d;
}

}  // namespace

std::optional<std::pair<Vec3, Vec3>> mediumFrame(const Vec3 &w) {
    const Vec3 s0 = kFrameDirection - w * dot(kFrameDirection, w);
    const double length = s0.length();
    if (!(length > 1e-9) || !std::isfinite(length)) return std::nullopt;
    const Vec3 s = s0 / length;
    return std::make_pair(s, cross(w, s));
}

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
    if (v.type == ManifoldVertexType::Medium) {
        const std::optional<MediumGeometry> g = mediumGeometry(prev, v, next);
        if (!g) return std::nullopt;
        return Vec2(dot(g->s, g->wOut), dot(g->t, g->wOut));
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
    if (v.type == ManifoldVertexType::Medium) return mediumDerivatives(prev, v, next);
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
    d.prevAxis = neighbourAxis(prev, wi, si, h, s, t);
    d.nextAxis = neighbourAxis(next, wo, so, h, s, t);

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
    if (scattering == Scattering::Medium) return m;
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
