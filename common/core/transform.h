// 4x4 affine/projective transforms with cached inverse (Mitsuba's Transform). Mitsuba's XML composes
// transform elements in document order: each new element is applied after the previous ones.
#pragma once
#include <array>

#include "core/vector.h"

namespace pf {

struct Matrix4 {
    std::array<std::array<double, 4>, 4> m{};
    static Matrix4 identity();
    Matrix4 operator*(const Matrix4 &o) const;
    // Returns false if the matrix is singular.
    bool inverse(Matrix4 &out) const;
    Matrix4 transposed() const;
    bool isFinite() const;
};

class Transform {
public:
    Transform() : m_(Matrix4::identity()), inv_(Matrix4::identity()) {}
    Transform(const Matrix4 &m, const Matrix4 &inv) : m_(m), inv_(inv) {}
    // Throws std::invalid_argument for a singular matrix.
    explicit Transform(const Matrix4 &m);

    static Transform translate(const Vec3 &v);
    static Transform scale(const Vec3 &v);
    static Transform rotate(const Vec3 &axis, double angleDeg);
    // Mitsuba's lookAt: columns (left, up, dir, origin), so the camera looks along local +z with +x to
    // the left of the image ("Mitsuba's handedness").
    static Transform lookAt(const Vec3 &origin, const Vec3 &target, const Vec3 &up);
    // Perspective projection in Mitsuba's convention (used by the perspective sensor).
    static Transform perspective(double fovDeg, double clipNear, double clipFar);

    Transform operator*(const Transform &o) const { return {m_ * o.m_, o.inv_ * inv_}; }
    Transform inverse() const { return {inv_, m_}; }
    const Matrix4 &matrix() const { return m_; }
    const Matrix4 &inverseMatrix() const { return inv_; }
    bool isIdentity() const;

    // point() and vector() are inline: cameras and instanced shapes call them on every ray and every
    // connection to the lens (issue 17).
    Vec3 point(const Vec3 &p) const {
        const auto &m = m_.m;
        const double x = m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3];
        const double y = m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3];
        const double z = m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3];
        const double w = m[3][0] * p.x + m[3][1] * p.y + m[3][2] * p.z + m[3][3];
        return w == 1.0 ? Vec3(x, y, z) : Vec3(x, y, z) / w;
    }
    Vec3 vector(const Vec3 &v) const {
        const auto &m = m_.m;
        return {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
                m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    }
    // Normals transform with the inverse transpose.
    Vec3 normal(const Vec3 &n) const;
    Ray ray(const Ray &r) const { return Ray(point(r.o), vector(r.d), r.tmin, r.tmax); }
    // True if the transform flips orientation (negative determinant of the linear part).
    bool flipsHandedness() const;

private:
    Matrix4 m_, inv_;
};

}  // namespace pf
