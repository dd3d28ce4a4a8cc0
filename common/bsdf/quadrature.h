// Composite Gauss-Legendre quadrature on [0, 1], for the few BSDF quantities that are integrals
// (diffuse Fresnel reflectance, rough-interface transmittance).
#pragma once
#include <array>

namespace pf {

// Positive nodes and weights of the 16-point Gauss-Legendre rule on [-1, 1] (Abramowitz & Stegun,
// table 25.4); the rule integrates polynomials up to degree 31 exactly.
constexpr std::array<double, 8> kGaussLegendre16Nodes = {0.0950125098376374, 0.2816035507792589, 0.4580167776572274,
                                                         0.6178762444026438, 0.7554044083550030, 0.8656312023878318,
                                                         0.9445750230732326, 0.9894009349916499};
constexpr std::array<double, 8> kGaussLegendre16Weights = {0.1894506104550685, 0.1826034150449236, 0.1691565193950025,
                                                           0.1495959888165767, 0.1246289712555339, 0.0951585116824928,
                                                           0.0622535239386479, 0.0271524594117541};

// Calls visit(x, w) for the nodes x and weights w of the 16-point rule composed over `panels` equal
// panels of [0, 1]; the weights sum to one.
template <typename Visit>
void forEachGaussLegendreNode(int panels, const Visit &visit) {
    const double h = 1.0 / panels;
    for (int p = 0; p < panels; ++p) {
        const double mid = (p + 0.5) * h;
        for (size_t i = 0; i < kGaussLegendre16Nodes.size(); ++i) {
            const double d = 0.5 * h * kGaussLegendre16Nodes[i], w = 0.5 * h * kGaussLegendre16Weights[i];
            visit(mid - d, w);
            visit(mid + d, w);
        }
    }
}

// \int_0^1 f(x) dx by the composite rule above.
template <typename F>
double integrateUnitInterval(const F &f, int panels) {
    double sum = 0.0;
    forEachGaussLegendreNode(panels, [&](double x, double w) { sum += w * f(x); });
    return sum;
}

}  // namespace pf
