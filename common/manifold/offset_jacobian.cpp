#include "manifold/offset_jacobian.h"

#include <algorithm>
#include <cmath>

#include "manifold/block_tridiagonal.h"
#include "manifold/dense_system.h"
#include "manifold/specular_constraint.h"

namespace pf {

namespace {

bool isMedium(const ManifoldVertex &v) { return v.type == ManifoldVertexType::Medium; }

// The factor for a chain with medium vertices (header): M is dense (dense_system.h), with a medium vertex's three
// coordinates (its chart and axis, an orthonormal basis: volume measure) and three rows (constraint and length).
// The vertices after x_b are walked from x_c, so their medium vertices' frames, offsets and segments are relative
// to their successor in chain order: they are rebuilt that way first, and their rows use it.
std::optional<double> mediumOffsetJacobian(const std::vector<ManifoldVertex> &chain, size_t free,
                                           const std::vector<size_t> &glossy) {
    const size_t k = chain.size();
    if (k < 3 || free + 1 >= k) return std::nullopt;
    std::vector<ManifoldVertex> c = chain;
    const auto walkedFromEnd = [&](size_t i) { return i > free && isMedium(c[i]); };
    for (size_t i = 1; i + 1 < k; ++i)
        if (walkedFromEnd(i)) {
            const std::optional<ManifoldVertex> v = ManifoldVertex::medium(chain[i].p, chain[i + 1].p, chain[i - 1].p);
            if (!v) return std::nullopt;
            c[i] = *v;
        }
    // Columns (and rows) of interior vertex i start at offset[i]; x_a and x_c are fixed and have none.
    std::vector<size_t> offset(k, 0);
    for (size_t i = 1; i + 1 < k; ++i) offset[i + 1] = offset[i] + (isMedium(c[i]) ? 3 : 2);
    const size_t dim = offset[k - 1];
    DenseSystem m(dim);
    const auto interior = [&](size_t i) { return i >= 1 && i + 1 < k; };
    // Writes ∂(row r, r + 1) along vertex q's coordinates: its chart block and, for a medium vertex, its axis.
    const auto put = [&](size_t r, size_t q, const Mat2 &block, const Vec2 &axis) {
        if (!interior(q)) return;
        for (int j = 0; j < 2; ++j) {
            m(r + j, offset[q]) = block(j, 0);
            m(r + j, offset[q] + 1) = block(j, 1);
            if (isMedium(c[q])) m(r + j, offset[q] + 2) = j == 0 ? axis.x : axis.y;
        }
    };
    for (size_t i = 1; i + 1 < k; ++i) {
        const size_t r = offset[i];
        if (free != 0 && i == free) {
            m(r, r) = m(r + 1, r + 1) = 1.0;
            continue;
        }
        // The predecessor in the direction the vertex was walked.
        const size_t pred = walkedFromEnd(i) ? i + 1 : i - 1, succ = 2 * i - pred;
        const std::optional<ConstraintDerivatives> d = constraintDerivatives(c[pred], c[i], c[succ]);
        if (!d) return std::nullopt;
        put(r, pred, d->prev, d->prevAxis);
        put(r, i, d->self, d->selfAxis);
        put(r, succ, d->next, d->nextAxis);
        if (!isMedium(c[i])) continue;
        // The segment |x_i - x_pred|: <ω_in, δx_i - δx_pred>.
        const Vec3 &w = c[i].n;
        m(r + 2, r + 2) = 1.0;
        if (interior(pred)) {
            const ManifoldVertex &p = c[pred];
            m(r + 2, offset[pred]) = -dot(w, p.dpdu);
            m(r + 2, offset[pred] + 1) = -dot(w, p.dpdv);
            if (isMedium(p)) m(r + 2, offset[pred] + 2) = -dot(w, p.n);
        }
    }
    // The columns of M^{-1} at the kept coordinates (x_b's, the glossy and medium vertices'), then their rows.
    std::vector<size_t> kept;
    std::vector<size_t> vertices = glossy;
    if (free != 0) vertices.push_back(free);
    std::sort(vertices.begin(), vertices.end());
    for (const size_t i : vertices)
        for (size_t j = offset[i]; j < offset[i] + (isMedium(c[i]) ? 3 : 2); ++j) kept.push_back(j);
    const size_t n = kept.size();
    std::vector<double> columns(dim * n, 0.0);
    for (size_t j = 0; j < n; ++j) columns[kept[j] * n + j] = 1.0;
    if (!m.solve(columns, n)) return std::nullopt;
    DenseSystem sub(n);
    for (size_t a = 0; a < n; ++a)
        for (size_t b = 0; b < n; ++b) sub(a, b) = columns[kept[a] * n + b];
    const double det = sub.absDeterminant();
    if (!(det > 0) || !std::isfinite(det)) return std::nullopt;
    return det;
}

}  // namespace

std::optional<double> offsetJacobian(const std::vector<ManifoldVertex> &chain, size_t free,
                                     const std::vector<size_t> &glossy) {
    if (glossy.empty()) return 1.0;
    if (std::any_of(chain.begin(), chain.end(), isMedium)) return mediumOffsetJacobian(chain, free, glossy);
    const size_t k = chain.size();
    if (k < 3 || free + 1 >= k) return std::nullopt;
    const bool hasFree = free != 0;
    // Block j of M is interior vertex j + 1; the blocks towards x_a and x_c are the fixed ends' B columns.
    const size_t n = k - 2;
    BlockTridiagonal m(n);
    for (size_t j = 0; j < n; ++j) {
        const size_t i = j + 1;
        if (hasFree && i == free) {
            m.diag(j) = Mat2::identity();
            continue;
        }
        const std::optional<ConstraintDerivatives> d = constraintDerivatives(chain[i - 1], chain[i], chain[i + 1]);
        if (!d) return std::nullopt;
        m.diag(j) = d->self;
        if (j > 0) m.lower(j) = d->prev;
        if (j + 1 < n) m.upper(j) = d->next;
    }
    if (!m.factorize()) return std::nullopt;
    double det;
    if (glossy.size() + (hasFree ? 1 : 0) == n) {
        det = 1 / m.determinant();
    } else {
        std::vector<size_t> blocks;
        if (hasFree) blocks.push_back(free - 1);
        for (const size_t g : glossy) blocks.push_back(g - 1);
        std::sort(blocks.begin(), blocks.end());
        det = m.inverseSubmatrixDeterminant(blocks);
    }
    det = std::abs(det);
    if (!(det > 0) || !std::isfinite(det)) return std::nullopt;
    return det;
}

}  // namespace pf
