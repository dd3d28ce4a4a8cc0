#include "path/portal_perturbation.h"

#include "scene/scene.h"

namespace pf {

PortalCrossing firstPortalCrossing(const Scene &scene, const PathView &x) {
    const auto &portals = scene.portals();
    PortalCrossing crossing;
    for (int i = x.length() - 3; i >= 0 && crossing.edge < 0; --i) {
        const Vec3 a = x.vertex(i).position(), b = x.vertex(i + 1).position();
        // The segment as a ray with t in (0, 1); the largest t is the crossing nearest the sensor.
        const Ray segment(a, b - a, 0, 1);
        double best = -1;
        for (size_t k = 0; k < portals.size(); ++k) {
            const double t = portals[k]->intersect(segment);
            if (t > best) {
                best = t;
                crossing = {i, static_cast<int>(k), segment(t)};
            }
        }
    }
    return crossing;
}

namespace {

// A vertex the perturbation may move: a non-specular surface (or emitter node at index 0) in vacuum.
bool movable(const PathVertex &v) {
    return isNonSpecular(v) && (v.type == VertexType::Surface || v.type == VertexType::EmitterNode);
}

}  // namespace

PortalPerturbation::PortalPerturbation(const Scene &scene, double r1, double r2) : scene_(scene), kernel_(r1, r2) {}

bool PortalPerturbation::applies(const PathView &x) const {
    if (scene_.portals().empty()) return false;
    const int i = firstPortalCrossing(scene_, x).edge;
    if (i < 0) return false;
    const PathEdge &edge = x.edge(i);
    return movable(x.vertex(i)) && movable(x.vertex(i + 1)) &&
           (i == 0 ? isJunction(x, -1) : isNonSpecular(x.vertex(i - 1))) && isNonSpecular(x.vertex(i + 2)) &&
           edge.medium == nullptr && edge.crossings == 0 && x.vertex(i + 1).type == VertexType::Surface &&
           (i == 0) == (x.vertex(i).type == VertexType::EmitterNode);
}

bool PortalPerturbation::turn(const Scene &scene, Sampler &sampler, const MutablePath &x,
                              const PortalCrossing &crossing, const Vec3 &w, MutablePath &y) const {
    const int i = crossing.edge;
    // The crossing point as a pass-through vertex in vacuum, from which both halves of the edge are traced.
    PathVertex p;
    p.type = VertexType::Medium;
    p.its.p = crossing.point;
    PathVertex a, b;
    PathEdge toSensor, toLight;
    // Towards the sensor side the emitter walk's rules apply (no environment), towards the light the sensor
    // walk's (an escaping ray reaches the environment's node).
    if (!p.perturb(scene, sampler, TransportMode::Importance, w, toSensor, b) ||
        !p.perturb(scene, sampler, TransportMode::Radiance, -w, toLight, a))
        return false;
    if (b.type != VertexType::Surface || toSensor.crossings > 0 || toLight.crossings > 0) return false;
    if (i == 0 ? !a.cast(scene, VertexType::EmitterNode) : a.type != VertexType::Surface) return false;
    y = x;
    y.vertex(i) = a;
    y.vertex(i + 1) = b;
    if (!movable(y.vertex(i)) || !movable(y.vertex(i + 1))) return false;
    return (i == 0 || connectJunction(scene, y, i - 1)) && connectJunction(scene, y, i) &&
           connectJunction(scene, y, i + 1);
}

bool PortalPerturbation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                MutationRecord &record) const {
    const PortalCrossing crossing = firstPortalCrossing(scene, x);
    const int i = crossing.edge;
    record = {i - 1, i + 2, 2};
    const Vec3 w = kernel_.sampleDirection(unitDirection(x.vertex(i), x.vertex(i + 1)), sampler.next2D());
    return turn(scene, sampler, x, crossing, w, y);
}

double PortalPerturbation::density(const Scene &scene, const PathView &x, const PathView &y,
                                   const MutationRecord &record) const {
    if (!applies(x) || y.length() != x.length()) return 0.0;
    const PortalCrossing crossing = firstPortalCrossing(scene, x);
    const int i = crossing.edge;
    if (record.l != i - 1) return 0.0;
    // y must be x's crossing edge turned about its crossing point: y's edge i crosses the same portal there.
    // (Whether y's own first crossing is that one decides whether the reverse move exists, density(y, x).)
    const Portal &portal = *scene.portals()[static_cast<size_t>(crossing.portal)];
    const PathVertex &a = y.vertex(i), &b = y.vertex(i + 1);
    const double length = (b.position() - a.position()).length();
    const Vec3 w = (b.position() - a.position()) / length;
    const Ray edge(a.position(), w, 0, length);
    const double t = portal.intersect(edge);
    if (t < 0 || (edge(t) - crossing.point).length() > 1e-5 * length) return 0.0;
    const double cosPortal = std::abs(dot(w, portal.normal()));
    const double g = a.cosine(w) * b.cosine(w) / (length * length);
    return cosPortal > 0 ? kernel_.directionPdf(unitDirection(x.vertex(i), x.vertex(i + 1)), w) * g / cosPortal : 0.0;
}

}  // namespace pf
