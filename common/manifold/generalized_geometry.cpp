#include "manifold/generalized_geometry.h"

#include <algorithm>

namespace pf {

namespace {

// D of §1.1 in the chart's measure: the cosine between the chart's normal and the edge for vertices on a
// surface or on the virtual plane; 1 for points, and for medium vertices (endpoints or in a chain) and
// FixedDirection vertices, whose charts are perpendicular to the edge already.
double chartCosine(const ManifoldVertex &v, const Vec3 &d) {
    return v.type == ManifoldVertexType::Surface || v.type == ManifoldVertexType::VirtualPlane ? absDot(v.ng, d) : 1.0;
}

}  // namespace

TangentSpace tangentSpace(const ChainJacobian &jacobian) {
    TangentSpace ts;
    const size_t n = jacobian.a.size();
    if (n == 0) return ts;
    const std::vector<Mat2> first = jacobian.a.inverseColumn(0);
    const std::vector<Mat2> last = jacobian.a.inverseColumn(n - 1);
    ts.wrtFirst.resize(n);
    ts.wrtLast.resize(n);
    for (size_t j = 0; j < n; ++j) {
        ts.wrtFirst[j] = -(first[j] * jacobian.bFirst);
        ts.wrtLast[j] = -(last[j] * jacobian.bLast);
    }
    return ts;
}

double geometryTerm(const ManifoldVertex &a, const ManifoldVertex &b) {
    const Vec3 delta = b.p - a.p;
    const double dist2 = delta.lengthSquared();
    if (!(dist2 > 0.0)) return 0.0;
    const Vec3 d = delta / std::sqrt(dist2);
    const double cosines = chartCosine(a, d) * chartCosine(b, d);
    if (a.type == ManifoldVertexType::FixedDirection || b.type == ManifoldVertexType::FixedDirection) return cosines;
    return cosines / dist2;
}

std::optional<double> generalizedGeometry(const std::vector<ManifoldVertex> &chain) {
    if (chain.size() < 2) return std::nullopt;
    if (chain.back().type == ManifoldVertexType::FixedDirection) return generalizedGeometry(reversedChain(chain));
    if (chain.size() == 2) return geometryTerm(chain[0], chain[1]);
    ChainJacobian jacobian;
    if (!jacobian.build(chain)) return std::nullopt;
    // P_first A^{-1} B_k: how the first unknown's chart moves with x_k (T_S up to sign).
    const double det = std::abs(jacobian.firstFromLast.determinant());
    // A FixedDirection x_0 is itself the first unknown: the determinant is already the ratio of area on its
    // plane ⟂ d (the beam's measure) to area at x_k.
    if (jacobian.unknowns[0] == 0) return det;
    return det * geometryTerm(chain[0], chain[1]);
}

}  // namespace pf
