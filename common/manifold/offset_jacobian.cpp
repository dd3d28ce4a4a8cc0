#include "manifold/offset_jacobian.h"

#include <algorithm>
#include <cmath>

#include "manifold/block_tridiagonal.h"
#include "manifold/specular_constraint.h"

namespace pf {

std::optional<double> offsetJacobian(const std::vector<ManifoldVertex> &chain, size_t free,
                                     const std::vector<size_t> &glossy) {
    if (glossy.empty()) return 1.0;
    // Medium vertices need their length rows (chain_jacobian.h) and the segment as a held coordinate: not done.
    if (std::any_of(chain.begin(), chain.end(),
                    [](const ManifoldVertex &v) { return v.type == ManifoldVertexType::Medium; }))
        return std::nullopt;
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
