// 2x2 matrices: the blocks of the specular constraint Jacobian (ALGORITHMS.md §6.2). Every vertex of a
// specular chain has two local coordinates, so the Jacobian of the stacked constraints is made of 2x2 blocks.
#pragma once
#include <cmath>

#include "core/vector.h"

namespace pf {

struct Mat2 {
    // Row-major: m[row][col].
    double m[2][2] = {{0.0, 0.0}, {0.0, 0.0}};

    Mat2() = default;
    Mat2(double a00, double a01, double a10, double a11) : m{{a00, a01}, {a10, a11}} {}
    static Mat2 identity() { return {1.0, 0.0, 0.0, 1.0}; }

    double operator()(int r, int c) const { return m[r][c]; }
    double &operator()(int r, int c) { return m[r][c]; }
    Mat2 operator+(const Mat2 &o) const {
        return {m[0][0] + o.m[0][0], m[0][1] + o.m[0][1], m[1][0] + o.m[1][0], m[1][1] + o.m[1][1]};
    }
    Mat2 operator-(const Mat2 &o) const {
        return {m[0][0] - o.m[0][0], m[0][1] - o.m[0][1], m[1][0] - o.m[1][0], m[1][1] - o.m[1][1]};
    }
    Mat2 operator-() const { return {-m[0][0], -m[0][1], -m[1][0], -m[1][1]}; }
    Mat2 operator*(double s) const { return {m[0][0] * s, m[0][1] * s, m[1][0] * s, m[1][1] * s}; }
    Mat2 operator*(const Mat2 &o) const {
        return {m[0][0] * o.m[0][0] + m[0][1] * o.m[1][0], m[0][0] * o.m[0][1] + m[0][1] * o.m[1][1],
                m[1][0] * o.m[0][0] + m[1][1] * o.m[1][0], m[1][0] * o.m[0][1] + m[1][1] * o.m[1][1]};
    }
    Vec2 operator*(const Vec2 &v) const { return {m[0][0] * v.x + m[0][1] * v.y, m[1][0] * v.x + m[1][1] * v.y}; }

    double determinant() const { return m[0][0] * m[1][1] - m[0][1] * m[1][0]; }
    double frobeniusNormSquared() const {
        return m[0][0] * m[0][0] + m[0][1] * m[0][1] + m[1][0] * m[1][0] + m[1][1] * m[1][1];
    }
    Mat2 transpose() const { return {m[0][0], m[1][0], m[0][1], m[1][1]}; }
    // Inverse through the adjugate. Returns false, leaving `inv` untouched, when the matrix is singular
    // relative to its own scale (|det| <= 1e-13 ||M||_F^2) or not finite: callers turn that into a failed
    // operation (a walk at a caustic fold, ALGORITHMS.md §6.3) rather than propagating NaN.
    bool invert(Mat2 &inv) const { return invert(inv, frobeniusNormSquared()); }
    // The same with the scale given: a matrix computed by cancellation (a pivot of block elimination) must be
    // judged against the size of the terms it came from, not against its own rounding residue.
    bool invert(Mat2 &inv, double referenceNormSquared) const {
        const double det = determinant();
        if (!std::isfinite(det) || !(std::abs(det) > 1e-13 * referenceNormSquared)) return false;
        const double r = 1.0 / det;
        inv = Mat2(m[1][1] * r, -m[0][1] * r, -m[1][0] * r, m[0][0] * r);
        return true;
    }
};

}  // namespace pf
