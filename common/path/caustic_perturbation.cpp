#include "path/caustic_perturbation.h"

namespace pf {

namespace {

// x_a, the non-specular vertex whose outgoing direction the perturbation changes, or -1 if the caustic
// perturbation does not apply: x_{n-2} must be non-specular (it connects to the camera), and x_a is the
// next non-specular vertex towards the light.
int causticSource(const PathView &x) {
    const int n = x.length();
    if (n < 3 || !isNonSpecular(x.vertex(n - 2))) return -1;
    int a = n - 3;
    while (a >= 0 && !isNonSpecular(x.vertex(a))) --a;
    return a;
}

}  // namespace

CausticPerturbation::CausticPerturbation(const PerturbationScale &scale) : scale_(scale) {}

bool CausticPerturbation::applies(const PathView &x) const { return causticSource(x) >= 0; }

ReciprocalKernel CausticPerturbation::angleKernel(const PathView &x) const {
    const int n = x.length(), a = causticSource(x);
    double lightSide = 0;
    for (int i = a; i < n - 2; ++i) lightSide += (x.vertex(i + 1).position() - x.vertex(i).position()).length();
    const double cameraSide = (x.vertex(n - 1).position() - x.vertex(n - 2).position()).length();
    // Where the light side is much shorter than the camera side the range would exceed a right angle,
    // beyond which directions wrap around: it is scaled down to end there, keeping its ratio.
    const double factor = std::min(scale_.radiansPerPixel * cameraSide / lightSide, kPi / 2 / scale_.r2);
    return ReciprocalKernel(scale_.r1 * factor, scale_.r2 * factor);
}

bool CausticPerturbation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                 MutationRecord &record) const {
    const int n = x.length(), a = causticSource(x);
    record = {a, n, n - 1 - a};
    const Vec3 d = angleKernel(x).sampleDirection(rayDirection(scene, x.vertex(a), x.vertex(a + 1)), sampler.next2D());
    y = x;
    return propagate(scene, sampler, TransportMode::Importance, x, y, a, n - 2, d) && connectJunction(scene, y, n - 2);
}

double CausticPerturbation::density(const Scene &scene, const PathView &x, const PathView &y,
                                    const MutationRecord &) const {
    const int n = x.length(), a = causticSource(x);
    if (a < 0 || y.length() != n || causticSource(y) != a) return 0.0;
    double density = angleKernel(x).directionPdf(rayDirection(scene, x.vertex(a), x.vertex(a + 1)),
                                                 rayDirection(scene, y.vertex(a), y.vertex(a + 1))) *
                     propagationJacobian(y, a, n - 2, TransportMode::Importance);
    for (int i = a + 1; i < n - 2; ++i) density *= importanceToCanonical(scene, y, i);
    return density;
}

}  // namespace pf
