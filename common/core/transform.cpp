#include "core/transform.h"

#include <stdexcept>

namespace pf {

Matrix4 Matrix4::identity() {
    Matrix4 r;
    for (int i = 0; i < 4; ++i) r.m[i][i] = 1.0;
    return r;
}

Matrix4 Matrix4::operator*(const Matrix4 &o) const {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

Matrix4 Matrix4::transposed() const {
    Matrix4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
    return r;
}

bool Matrix4::isFinite() const {
    for (const auto &row : m)
        for (double v : row)
            if (!std::isfinite(v)) return false;
    return true;
}

// Gauss-Jordan elimination with partial pivoting.
bool Matrix4::inverse(Matrix4 &out) const {
    double a[4][8];
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            a[i][j] = m[i][j];
            a[i][j + 4] = (i == j) ? 1.0 : 0.0;
        }
    for (int c = 0; c < 4; ++c) {
        int piv = c;
        for (int r = c + 1; r < 4; ++r)
            if (std::abs(a[r][c]) > std::abs(a[piv][c])) piv = r;
        if (std::abs(a[piv][c]) < 1e-300) return false;
        if (piv != c)
            for (int j = 0; j < 8; ++j) std::swap(a[c][j], a[piv][j]);
        const double inv = 1.0 / a[c][c];
        for (int j = 0; j < 8; ++j) a[c][j] *= inv;
        for (int r = 0; r < 4; ++r) {
            if (r == c) continue;
            const double f = a[r][c];
            if (f == 0) continue;
            for (int j = 0; j < 8; ++j) a[r][j] -= f * a[c][j];
        }
    }
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) out.m[i][j] = a[i][j + 4];
    return true;
}

Transform::Transform(const Matrix4 &m) : m_(m) {
    if (!m.isFinite() || !m.inverse(inv_)) throw std::invalid_argument("singular or non-finite transform matrix");
}

Transform Transform::translate(const Vec3 &v) {
    Matrix4 m = Matrix4::identity(), inv = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        m.m[i][3] = v[i];
        inv.m[i][3] = -v[i];
    }
    return {m, inv};
}

Transform Transform::scale(const Vec3 &v) {
    if (v.x == 0 || v.y == 0 || v.z == 0) throw std::invalid_argument("scale by zero");
    Matrix4 m = Matrix4::identity(), inv = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        m.m[i][i] = v[i];
        inv.m[i][i] = 1.0 / v[i];
    }
    return {m, inv};
}

Transform Transform::rotate(const Vec3 &axisIn, double angleDeg) {
    if (axisIn.isZero()) throw std::invalid_argument("rotation about a zero axis");
    const Vec3 a = normalize(axisIn);
    const double s = std::sin(degToRad(angleDeg)), c = std::cos(degToRad(angleDeg));
    Matrix4 m = Matrix4::identity();
    m.m[0][0] = a.x * a.x + (1 - a.x * a.x) * c;
    m.m[0][1] = a.x * a.y * (1 - c) - a.z * s;
    m.m[0][2] = a.x * a.z * (1 - c) + a.y * s;
    m.m[1][0] = a.x * a.y * (1 - c) + a.z * s;
    m.m[1][1] = a.y * a.y + (1 - a.y * a.y) * c;
    m.m[1][2] = a.y * a.z * (1 - c) - a.x * s;
    m.m[2][0] = a.x * a.z * (1 - c) - a.y * s;
    m.m[2][1] = a.y * a.z * (1 - c) + a.x * s;
    m.m[2][2] = a.z * a.z + (1 - a.z * a.z) * c;
    return {m, m.transposed()};
}

Transform Transform::lookAt(const Vec3 &origin, const Vec3 &target, const Vec3 &up) {
    const Vec3 dir = normalize(target - origin);
    const Vec3 left = cross(up, dir);
    if (!(left.length() > 1e-12)) throw std::invalid_argument("lookat: 'up' is parallel to the viewing direction");
    const Vec3 l = normalize(left);
    const Vec3 newUp = cross(dir, l);
    Matrix4 m = Matrix4::identity();
    for (int i = 0; i < 3; ++i) {
        m.m[i][0] = l[i];
        m.m[i][1] = newUp[i];
        m.m[i][2] = dir[i];
        m.m[i][3] = origin[i];
    }
    return Transform(m);
}

Transform Transform::perspective(double fovDeg, double n, double f) {
    // Mitsuba's Transform::perspective: maps the view frustum to [-1,1]^2 x [0,1].
    const double recip = 1.0 / (f - n);
    const double cot = 1.0 / std::tan(degToRad(fovDeg / 2.0));
    Matrix4 m;
    m.m[0][0] = cot;
    m.m[1][1] = cot;
    m.m[2][2] = f * recip;
    m.m[2][3] = -n * f * recip;
    m.m[3][2] = 1;
    return Transform(m);
}

bool Transform::isIdentity() const {
    const Matrix4 id = Matrix4::identity();
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            if (m_.m[i][j] != id.m[i][j]) return false;
    return true;
}

Vec3 Transform::normal(const Vec3 &n) const {
    const auto &i = inv_.m;
    return {i[0][0] * n.x + i[1][0] * n.y + i[2][0] * n.z, i[0][1] * n.x + i[1][1] * n.y + i[2][1] * n.z,
            i[0][2] * n.x + i[1][2] * n.y + i[2][2] * n.z};
}

bool Transform::flipsHandedness() const {
    const auto &m = m_.m;
    const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                       m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                       m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    return det < 0;
}

}  // namespace pf
