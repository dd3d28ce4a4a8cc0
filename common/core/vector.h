// Small fixed-size vectors in double precision. Geometry is kept in double throughout the renderer
// because the manifold walks of ALGORITHMS.md §6 solve Newton systems on path vertices.
#pragma once
#include <cmath>
#include <ostream>

#include "core/math.h"

namespace pf {

struct Vec2 {
    double x = 0, y = 0;
    Vec2() = default;
    Vec2(double x_, double y_) : x(x_), y(y_) {}
    Vec2 operator+(const Vec2 &o) const { return {x + o.x, y + o.y}; }
    Vec2 operator-(const Vec2 &o) const { return {x - o.x, y - o.y}; }
    Vec2 operator*(double s) const { return {x * s, y * s}; }
    double operator[](int i) const { return i == 0 ? x : y; }
    double &operator[](int i) { return i == 0 ? x : y; }
};

struct Vec3 {
    double x = 0, y = 0, z = 0;
    Vec3() = default;
    Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
    explicit Vec3(double v) : x(v), y(v), z(v) {}
    Vec3 operator+(const Vec3 &o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3 &o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator*(double s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(double s) const { return *this * (1.0 / s); }
    Vec3 &operator+=(const Vec3 &o) { x += o.x; y += o.y; z += o.z; return *this; }
    Vec3 &operator-=(const Vec3 &o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
    Vec3 &operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
    bool operator==(const Vec3 &o) const { return x == o.x && y == o.y && z == o.z; }
    double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    double &operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    double lengthSquared() const { return x * x + y * y + z * z; }
    double length() const { return std::sqrt(lengthSquared()); }
    bool isZero() const { return x == 0 && y == 0 && z == 0; }
    bool isFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }
};

inline Vec3 operator*(double s, const Vec3 &v) { return v * s; }
inline double dot(const Vec3 &a, const Vec3 &b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double absDot(const Vec3 &a, const Vec3 &b) { return std::abs(dot(a, b)); }
inline Vec3 cross(const Vec3 &a, const Vec3 &b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline Vec3 normalize(const Vec3 &v) { return v / v.length(); }
inline Vec3 vmin(const Vec3 &a, const Vec3 &b) {
    return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 vmax(const Vec3 &a, const Vec3 &b) {
    return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}
inline Vec3 faceForward(const Vec3 &n, const Vec3 &v) { return dot(n, v) < 0 ? -n : n; }
inline std::ostream &operator<<(std::ostream &os, const Vec3 &v) {
    return os << "[" << v.x << ", " << v.y << ", " << v.z << "]";
}

// Reflection and refraction in a local frame whose normal is +z (Mitsuba's convention: both
// directions point away from the surface).
inline Vec3 reflect(const Vec3 &wi) { return {-wi.x, -wi.y, wi.z}; }
inline Vec3 reflect(const Vec3 &wi, const Vec3 &m) { return 2.0 * dot(wi, m) * m - wi; }

struct AABB {
    Vec3 min{kInfinity, kInfinity, kInfinity};
    Vec3 max{-kInfinity, -kInfinity, -kInfinity};
    void expand(const Vec3 &p) { min = vmin(min, p); max = vmax(max, p); }
    void expand(const AABB &b) { min = vmin(min, b.min); max = vmax(max, b.max); }
    bool valid() const { return min.x <= max.x && min.y <= max.y && min.z <= max.z; }
    Vec3 center() const { return (min + max) * 0.5; }
    Vec3 extents() const { return max - min; }
};

struct Ray {
    Vec3 o, d;
    double tmin = 0, tmax = kInfinity;
    Ray() = default;
    Ray(const Vec3 &o_, const Vec3 &d_, double tmin_ = 0, double tmax_ = kInfinity)
        : o(o_), d(d_), tmin(tmin_), tmax(tmax_) {}
    Vec3 operator()(double t) const { return o + d * t; }
};

}  // namespace pf
