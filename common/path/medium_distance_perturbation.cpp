#include "path/medium_distance_perturbation.h"

#include <algorithm>
#include <cmath>

#include "scene/scene.h"

namespace pf {

namespace {

// y's vertex i moved to p: its edge from the anchor j is rebuilt (connect walks from the light side). The edge
// may cross index-matched boundaries: the vertex then lies in the medium beyond the last one it crosses from the
// anchor (mediumAt()), and its wi points to its predecessor in its walk.
bool moveAlongEdge(const Scene &scene, MutablePath &y, int i, int j, const Vec3 &p) {
    PathVertex &v = y.vertex(i);
    v.its.p = p;
    v.medium = mediumAt(scene, y.vertex(j), p);
    if (!v.medium) return false;
    const int pred = v.walkMode == TransportMode::Importance ? i - 1 : i + 1;
    v.its.wi = normalize(y.vertex(pred).position() - p);
    const int lo = std::min(i, j);
    return connect(scene, y.vertex(lo), y.vertex(lo + 1), y.edge(lo));
}

}  // namespace

MediumDistancePerturbation::MediumDistancePerturbation() : kernel_(0.01, 1.0) {}

std::vector<MediumDistancePerturbation::Source> MediumDistancePerturbation::sources(const PathView &x) const {
    std::vector<Source> list;
    const int n = x.length();
    for (int i = 1; i + 1 < n; ++i) {
        if (x.vertex(i).type != VertexType::Medium) continue;
        for (const int j : {i - 1, i + 1}) {
            const int k = 2 * i - j;
            if (isJunction(x, std::min(i, k))) list.push_back({i, j});
        }
    }
    return list;
}

bool MediumDistancePerturbation::sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                                        MutationRecord &record) const {
    const std::vector<Source> list = sources(x);
    if (list.empty()) return false;
    const Source s = list[std::min(list.size() - 1, static_cast<size_t>(sampler.next1D() * list.size()))];
    const double r = kernel_.sample(sampler.next1D());
    const double factor = std::exp(sampler.next1D() < 0.5 ? r : -r);
    const int i = s.vertex, j = s.anchor, k = 2 * i - j;
    record = {i - 1, i + 1, 1, j, i};
    y = x;
    const Vec3 &anchor = x.vertex(j).position();
    if (!moveAlongEdge(scene, y, i, j, anchor + (x.vertex(i).position() - anchor) * factor)) return false;
    return connectJunction(scene, y, std::min(i, k));
}

double MediumDistancePerturbation::density(const Scene &, const PathView &x, const PathView &y,
                                           const MutationRecord &record) const {
    const int i = record.moving, j = record.source;
    if (y.length() != x.length() || i != record.l + 1 || record.m != i + 1 || std::abs(i - j) != 1) return 0.0;
    const std::vector<Source> list = sources(x);
    if (std::none_of(list.begin(), list.end(), [&](const Source &s) { return s.vertex == i && s.anchor == j; }))
        return 0.0;
    const PathVertex &v = y.vertex(i);
    if (v.type != VertexType::Medium) return 0.0;
    // y's x_i must lie on x's edge from the anchor (the Dirac delta in ω), on the same side.
    const Vec3 &anchor = x.vertex(j).position();
    const Vec3 from = x.vertex(i).position() - anchor, to = v.position() - anchor;
    const double t = from.length(), tNew = to.length();
    if (!(t > 0) || !(tNew > 0) || cross(from / t, to / tNew).length() > 1e-6 || dot(from, to) <= 0) return 0.0;
    const double q = kernel_.pdf(std::abs(std::log(tNew / t))) / (2 * tNew);
    return q / (tNew * tNew) / static_cast<double>(list.size());
}

}  // namespace pf
