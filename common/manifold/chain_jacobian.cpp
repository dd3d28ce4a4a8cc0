#include "manifold/chain_jacobian.h"

#include <algorithm>
#include <cmath>

#include "manifold/dense_system.h"
#include "manifold/specular_constraint.h"

namespace pf {

namespace {

bool isMedium(const ManifoldVertex &v) { return v.type == ManifoldVertexType::Medium; }

// The layout rules of chain_jacobian.h: constrained interior (surfaces or media), unconstrained last vertex,
// FixedDirection first if anywhere.
bool validLayout(const std::vector<ManifoldVertex> &chain) {
    const size_t k = chain.size();
    if (k < 2) return false;
    for (size_t i = 1; i + 1 < k; ++i) {
        const ManifoldVertex &v = chain[i];
        if (v.scattering == Scattering::None) return false;
        if (v.type != ManifoldVertexType::Surface && !isMedium(v)) return false;
    }
    if (chain[0].scattering != Scattering::None) return false;
    return !chain[k - 1].isConstrained();
}

}  // namespace

bool ChainJacobian::build(const std::vector<ManifoldVertex> &chain) {
    singular = false;
    dense = false;
    unknowns.clear();
    bFirst = bLast = firstFromLast = Mat2();
    if (!validLayout(chain)) return false;
    const size_t k = chain.size();
    if (chain[0].type == ManifoldVertexType::FixedDirection) unknowns.push_back(0);
    for (size_t i = 1; i + 1 < k; ++i) unknowns.push_back(i);
    if (std::any_of(chain.begin(), chain.end(), isMedium)) {
        dense = true;
        a.resize(0);
        return buildDense(chain);
    }
    const size_t n = unknowns.size();
    a.resize(n);
    for (size_t j = 0; j < n; ++j) {
        const size_t c = unknowns[j];
        const ManifoldVertex &prev = c > 0 ? chain[c - 1] : chain[c];
        const std::optional<ConstraintDerivatives> d = constraintDerivatives(prev, chain[c], chain[c + 1]);
        if (!d) return false;
        a.diag(j) = d->self;
        if (j > 0)
            a.lower(j) = d->prev;
        else if (c > 0)
            bFirst = d->prev;
        if (j + 1 < n)
            a.upper(j) = d->next;
        else
            bLast = d->next;
    }
    if (!a.factorize()) {
        singular = true;
        return false;
    }
    if (n > 0) firstFromLast = a.inverseColumn(n - 1)[0] * bLast;
    return true;
}

// The system of chain_jacobian.h with medium vertices: per unknown its coordinates (chart u, v, and the axis of
// a medium vertex) as columns, its constraint's two rows and a medium vertex's length row; the right-hand side
// is B_k (two columns), in the last unknown's constraint rows.
bool ChainJacobian::buildDense(const std::vector<ManifoldVertex> &chain) {
    const size_t n = unknowns.size();
    if (n == 0) return true;
    // Offsets of each unknown's columns (and rows: a vertex has as many rows as coordinates).
    std::vector<size_t> offset(n + 1, 0);
    for (size_t j = 0; j < n; ++j) offset[j + 1] = offset[j] + (isMedium(chain[unknowns[j]]) ? 3 : 2);
    const size_t dim = offset[n];
    DenseSystem m(dim);
    std::vector<double> rhs(dim * 2, 0.0);
    // Writes a 2x2 block and, for a medium vertex, its axis column into rows r, r + 1 at unknown j's columns.
    const auto put = [&](size_t r, size_t j, const Mat2 &block, const Vec2 &axis) {
        const size_t c = offset[j];
        for (int i = 0; i < 2; ++i) {
            m(r + i, c) = block(i, 0);
            m(r + i, c + 1) = block(i, 1);
            if (offset[j + 1] - c == 3) m(r + i, c + 2) = i == 0 ? axis.x : axis.y;
        }
    };
    for (size_t j = 0; j < n; ++j) {
        const size_t c = unknowns[j], r = offset[j];
        const ManifoldVertex &prev = c > 0 ? chain[c - 1] : chain[c], &v = chain[c];
        const std::optional<ConstraintDerivatives> d = constraintDerivatives(prev, v, chain[c + 1]);
        if (!d) return false;
        put(r, j, d->self, d->selfAxis);
        if (j > 0) put(r, j - 1, d->prev, d->prevAxis);
        if (j + 1 < n) {
            put(r, j + 1, d->next, d->nextAxis);
        } else {
            for (int i = 0; i < 2; ++i) {
                rhs[(r + i) * 2] = d->next(i, 0);
                rhs[(r + i) * 2 + 1] = d->next(i, 1);
            }
        }
        if (!isMedium(v)) continue;
        // The length row <ω_in, δx_i - δx_{i-1}> = 0; x_{i-1} is fixed unless it is an unknown too.
        const Vec3 &w = v.n;
        m(r + 2, r) = dot(w, v.dpdu);
        m(r + 2, r + 1) = dot(w, v.dpdv);
        m(r + 2, r + 2) = 1.0;
        if (j > 0) {
            const size_t pc = offset[j - 1];
            m(r + 2, pc) = -dot(w, prev.dpdu);
            m(r + 2, pc + 1) = -dot(w, prev.dpdv);
            if (offset[j] - pc == 3) m(r + 2, pc + 2) = -dot(w, prev.n);
        }
    }
    if (!m.solve(rhs, 2)) {
        singular = true;
        return false;
    }
    firstFromLast = Mat2(rhs[0], rhs[1], rhs[2], rhs[3]);
    return true;
}

}  // namespace pf
