// Orthonormal frames: the local shading space of BSDFs (normal = +z), as in Mitsuba's Frame.
#pragma once
#include "core/vector.h"

namespace pf {

// Duff et al. 2017, "Building an Orthonormal Basis, Revisited": continuous almost everywhere and
// branch-light. The manifold code relies on frames that vary continuously (ALGORITHMS.md §9.2).
inline void coordinateSystem(const Vec3 &n, Vec3 &s, Vec3 &t) {
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = n.x * n.y * a;
    s = Vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    t = Vec3(b, sign + n.y * n.y * a, -n.y);
}

struct Frame {
    Vec3 s{1, 0, 0}, t{0, 1, 0}, n{0, 0, 1};
    Frame() = default;
    explicit Frame(const Vec3 &normal) : n(normal) { coordinateSystem(n, s, t); }
    Frame(const Vec3 &s_, const Vec3 &t_, const Vec3 &n_) : s(s_), t(t_), n(n_) {}
    // Gram-Schmidt a frame from a normal and a tangent hint (e.g. dp/du).
    static Frame fromNormalTangent(const Vec3 &n, const Vec3 &dpdu) {
        Vec3 s = dpdu - n * dot(n, dpdu);
        const double len = s.length();
        if (!(len > 1e-12)) return Frame(n);
        s = s / len;
        return Frame(s, cross(n, s), n);
    }
    Vec3 toLocal(const Vec3 &v) const { return {dot(v, s), dot(v, t), dot(v, n)}; }
    Vec3 toWorld(const Vec3 &v) const { return s * v.x + t * v.y + n * v.z; }

    static double cosTheta(const Vec3 &v) { return v.z; }
    static double cos2Theta(const Vec3 &v) { return v.z * v.z; }
    static double sin2Theta(const Vec3 &v) { return std::max(0.0, 1.0 - v.z * v.z); }
    static double sinTheta(const Vec3 &v) { return std::sqrt(sin2Theta(v)); }
    static double tanTheta(const Vec3 &v) { return sinTheta(v) / v.z; }
    static double tan2Theta(const Vec3 &v) { return sin2Theta(v) / (v.z * v.z); }
    static double cosPhi(const Vec3 &v) {
        const double st = sinTheta(v);
        return st == 0 ? 1.0 : clamp(v.x / st, -1.0, 1.0);
    }
    static double sinPhi(const Vec3 &v) {
        const double st = sinTheta(v);
        return st == 0 ? 0.0 : clamp(v.y / st, -1.0, 1.0);
    }
};

}  // namespace pf
