// The determinant factor of the glossy manifold perturbation ([TR eq. 12, §5.2], [TH eq. 6.3]; ALGORITHMS.md
// §6.6): the Jacobian |∂[x_b, x_{i1} … x_{ik}] / ∂[x_b, o_{i1} … o_{ik}]| between the positions of the glossy
// vertices walked as specular ones (x_{i1} … x_{ik}) and their offsets o = T^T h, with the freely moving vertex
// x_b and the chain's ends x_a, x_c held fixed.
//
// With the ends fixed, the map F(x_{a+1} … x_{c-1}) = (c_{a+1} … c_{b-1}, x_b, c_{b+1} … c_{c-1}) has the
// block-tridiagonal Jacobian M: the A-type matrix of ∇C over the interior, whose x_b block row is replaced by
// [0 … I_2 … 0]. Its inverse is ∂x / ∂(o, x_b) with every offset free; the ideal specular vertices keep o = 0,
// so their columns drop out, and they are measured by the pseudo-measure rather than by area, so their rows
// drop out too. What remains is the submatrix of M^{-1} on x_b's and the glossy vertices' rows and columns.
// x_b's row of M^{-1} is the identity row, so the determinant is that of the glossy vertices' submatrix.
// When every interior vertex but x_b is glossy the submatrix is M^{-1} itself and the factor is 1 / |det M|,
// the cheap form of [TR §5.2].
//
// Charts are orthonormal (manifold_vertex.h), so the factor is in the area measure of the glossy vertices.
#pragma once
#include <cstddef>
#include <optional>
#include <vector>

#include "manifold/manifold_vertex.h"

namespace pf {

// The factor for chain x_a … x_c (chain order; ends unconstrained), whose vertex `free` (an interior index)
// is the unconstrained x_b and whose other interior vertices are constrained (free = 0: x_b is the end x_a
// itself, as for the endpoint position perturbation, and M is the A-type matrix of the interior); `glossy` lists the
// interior indices of the glossy ones (offset manifolds), the rest being ideal specular. 1 without glossy vertices.
// nullopt on a degenerate chain or a singular M (a caustic fold).
//
// Medium vertices (§6.7) in `glossy` are held at their offset and their segment length: the factor is then
// |∂[x_b, x_g.., x_m..] / ∂[x_b, o_g.., (o_m, ℓ_m)..]|, in the volume measure at each medium vertex x_m, with the
// length rows of chain_jacobian.h. The vertices before x_b were walked from x_a (as listed), those after it from
// x_c, so a medium vertex after x_b has its frame, offset and segment relative to its successor in the list.
std::optional<double> offsetJacobian(const std::vector<ManifoldVertex> &chain, size_t free,
                                     const std::vector<size_t> &glossy);

}  // namespace pf
