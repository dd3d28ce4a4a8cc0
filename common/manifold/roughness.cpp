#include "manifold/roughness.h"

#include <algorithm>
#include <cmath>

#include "core/math.h"

namespace pf {

double beckmannQuantileAngle(double alpha, double q) {
    if (std::isinf(alpha)) return kPi / 2;
    return std::atan(-alpha * alpha * std::log1p(-q));
}

double hgQuantileAngle(double g, double q) {
    const double a = std::abs(g), g2 = 1 + g * g, d = 1 + a - 2 * a * q;
    const double cosTheta = ((1 + a) * (1 + a) - 2 * (1 + a) * g2 * q + 2 * a * g2 * q * q) / (d * d);
    return std::acos(std::clamp(cosTheta, -1.0, 1.0));
}

double nonSpecularProbability(double thetaQ, double dtheta) {
    // 1 - cos x = 2 sin^2(x / 2) keeps the digits of small angles (theta_q ~ 1e-2 for alpha = 0.1).
    const auto oneMinusCos = [](double x) {
        const double s = std::sin(x / 2);
        return 2 * s * s;
    };
    const double denominator = oneMinusCos(std::min(thetaQ + dtheta, kPi));
    return denominator > 0 ? std::min(1.0, oneMinusCos(thetaQ) / denominator) : 0.0;
}

double specularProbability(double thetaQ, double dtheta) { return 1 - nonSpecularProbability(thetaQ, dtheta); }

double nonSpecularProbabilitySurface(double alpha, double dtheta) {
    if (alpha <= 0) return 0.0;
    if (std::isinf(alpha)) return 1.0;
    return nonSpecularProbability(beckmannQuantileAngle(alpha), dtheta);
}

}  // namespace pf
