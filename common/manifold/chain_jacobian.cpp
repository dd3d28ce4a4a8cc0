#include "manifold/chain_jacobian.h"

#include "manifold/specular_constraint.h"

namespace pf {

namespace {

// The layout rules of chain_jacobian.h: constrained interior, unconstrained last vertex, FixedDirection first
// if anywhere.
bool validLayout(const std::vector<ManifoldVertex> &chain) {
    const size_t k = chain.size();
    if (k < 2) return false;
    for (size_t i = 1; i + 1 < k; ++i)
        if (chain[i].type != ManifoldVertexType::Surface || chain[i].scattering == Scattering::None) return false;
    if (chain[0].scattering != Scattering::None) return false;
    return !chain[k - 1].isConstrained();
}

}  // namespace

bool ChainJacobian::build(const std::vector<ManifoldVertex> &chain) {
    singular = false;
    unknowns.clear();
    bFirst = bLast = Mat2();
    if (!validLayout(chain)) return false;
    const size_t k = chain.size();
    if (chain[0].type == ManifoldVertexType::FixedDirection) unknowns.push_back(0);
    for (size_t i = 1; i + 1 < k; ++i) unknowns.push_back(i);
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
    return true;
}

}  // namespace pf
