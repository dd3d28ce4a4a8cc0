#include "path/mutation.h"

#include "bsdf/bsdf.h"
#include "scene/scene.h"

namespace pf {

MutablePath::MutablePath(const PathView &view) {
    const int n = view.length();
    for (int i = -1; i <= n; ++i) vertices_.push_back(view.vertex(i));
    edges_.emplace_back();
    for (int i = 0; i + 1 < n; ++i) edges_.push_back(view.edge(i));
    edges_.emplace_back();
    publish();
}

MutablePath &MutablePath::operator=(const MutablePath &other) {
    vertices_ = other.vertices_;
    edges_ = other.edges_;
    publish();
    return *this;
}

MutablePath &MutablePath::operator=(MutablePath &&other) noexcept {
    vertices_ = std::move(other.vertices_);
    edges_ = std::move(other.edges_);
    publish();
    other.publish();
    return *this;
}

void MutablePath::publish() {
    // An empty path (length -2) publishes nothing; every path with vertices has the two supernode edges.
    if (vertices_.empty())
        PathView::publish(nullptr, nullptr, -2);
    else
        PathView::publish(vertices_.data(), edges_.data() + 1, static_cast<int>(vertices_.size()) - 2);
}

void MutablePath::splice(const MutablePath &x, int l, int m, int added) {
    const int n = x.length();
    vertices_.assign(x.vertices_.begin(), x.vertices_.begin() + (l + 2));
    vertices_.resize(vertices_.size() + static_cast<size_t>(added));
    vertices_.insert(vertices_.end(), x.vertices_.begin() + (m + 1), x.vertices_.end());
    edges_.assign(x.edges_.begin(), x.edges_.begin() + (l + 1));
    edges_.resize(edges_.size() + static_cast<size_t>(added + 1));
    edges_.insert(edges_.end(), x.edges_.begin() + (m + 1), x.edges_.begin() + (n + 1));
    publish();
}

Spectrum chainContribution(const Scene &scene, const PathView &path) {
    return contribution(scene, path, TransportMode::Radiance);
}

namespace {

// Vertex i's factors of f as the walk of `mode` evaluates them: EVAL and the cosine towards the walk's
// predecessor (path/path.h: contribution()).
double vertexTerm(const Scene &scene, const PathView &path, int i, TransportMode mode) {
    const PathVertex &v = path.vertex(i);
    const int back = mode == TransportMode::Importance ? -1 : 1;
    const PathVertex &pred = path.vertex(i + back), &succ = path.vertex(i - back);
    double term = v.eval(scene, &pred, succ, mode).luminance();
    if (!pred.isSupernode()) term *= v.cosine(normalize(pred.position() - v.position()));
    return term;
}

}  // namespace

double importanceToCanonical(const Scene &scene, const PathView &path, int i) {
    if (!path.vertex(i).delta) return 1.0;
    const double importance = vertexTerm(scene, path, i, TransportMode::Importance);
    return importance > 0 ? vertexTerm(scene, path, i, TransportMode::Radiance) / importance : 0.0;
}

const char *mutationName(MutationType type) {
    switch (type) {
        case MutationType::Bidirectional:
            return "bidirectional";
        case MutationType::LensSubpath:
            return "lensSubpath";
        case MutationType::Lens:
            return "lens";
        case MutationType::Caustic:
            return "caustic";
        case MutationType::MultiChain:
            return "multiChain";
        case MutationType::Manifold:
            return "manifold";
        case MutationType::MediumDistance:
            return "mediumDistance";
        case MutationType::Portal:
            return "portal";
    }
    return "";
}

uint64_t MutationSet::applicable(const PathView &x) const {
    uint64_t mask = 0;
    for (size_t k = 0; k < mutations_.size(); ++k)
        if (mutations_[k]->applies(x)) mask |= uint64_t(1) << k;
    return mask;
}

double MutationSet::selectionProbability(uint64_t mask, size_t k) const {
    if (!(mask >> k & 1)) return 0.0;
    double total = 0;
    for (size_t j = 0; j < mutations_.size(); ++j) total += mask >> j & 1 ? weights_[j] : 0;
    return weights_[k] / total;
}

int MutationSet::select(uint64_t mask, double u) const {
    if (mask == 0) return -1;
    double total = 0;
    for (size_t k = 0; k < mutations_.size(); ++k)
        if (mask >> k & 1) total += weights_[k];
    double below = 0;
    int last = -1;
    for (size_t k = 0; k < mutations_.size(); ++k) {
        if (!(mask >> k & 1)) continue;
        below += weights_[k];
        last = static_cast<int>(k);
        if (u * total < below) return last;
    }
    return last;
}

bool extendWalk(const Scene &scene, Sampler &sampler, TransportMode mode, MutablePath &y, int from, int steps) {
    const int dir = mode == TransportMode::Importance ? 1 : -1;
    PathVertex &start = y.vertex(from);
    if (!start.isSupernode() && steps > 0) {
        // The kept vertex now continues a walk of `mode`: it arrives from its neighbour on the other side.
        const PathVertex &pred = y.vertex(from - dir);
        const Vec3 toPred = normalize(pred.position() - start.position());
        if (start.type == VertexType::Surface) start.its.wi = start.its.toLocal(toPred);
        if (start.type == VertexType::Medium) start.its.wi = toPred;
        start.walkMode = mode;
        // SAMPLENEXT ends a walk whose throughput vanishes; mutations only use the walk's vertices (a vertex
        // made by a perturbation carries none), so the walk starts from unit throughput.
        start.throughput = Spectrum(1.0);
    }
    const Film &film = scene.sensor().film();
    for (int k = 0, cur = from; k < steps; ++k, cur += dir) {
        PathVertex &v = y.vertex(cur);
        if (v.type == VertexType::SensorNode)
            v.ps.uv = Vec2(sampler.next1D() * film.cropWidth(), sampler.next1D() * film.cropHeight());
        const PathVertex *pred = v.isSupernode() ? nullptr : &y.vertex(cur - dir);
        // Sampled straight into y (sampleNext overwrites it whole; a failed walk's y is unused) instead of
        // copying a 496-byte vertex per step (issue 17).
        PathVertex &succ = y.vertex(cur + dir);
        PathEdge edge;
        if (!v.sampleNext(scene, sampler, mode, pred, edge, succ)) return false;
        // A sensor walk that left the scene reached the environment's emitter node: it cannot go on.
        if (succ.isEndpointNode() && !v.isSupernode() && k + 1 < steps) return false;
        if (!v.isSupernode() && !succ.isSupernode()) y.edge(std::min(cur, cur + dir)) = edge;
    }
    return true;
}

bool isJunction(const PathView &y, int i) {
    if (i < 0) {
        const PathVertex &v = y.vertex(0);
        return v.type == VertexType::EmitterNode && !v.hasDeltaPosition();
    }
    const PathVertex &a = y.vertex(i), &b = y.vertex(i + 1);
    // The emitter side of an endpoint pair must be an emitter node and the sensor side a sensor node.
    return isNonSpecular(a) && isNonSpecular(b) && a.type != VertexType::SensorNode &&
           b.type != VertexType::EmitterNode;
}

bool connectJunction(const Scene &scene, MutablePath &y, int i) {
    if (i < 0) return y.vertex(0).cast(scene, VertexType::EmitterNode) && isJunction(y, i);
    PathVertex &a = y.vertex(i), &b = y.vertex(i + 1);
    a.delta = b.delta = false;
    if (!isJunction(y, i)) return false;
    if (b.type == VertexType::SensorNode &&
        !scene.sensor().rasterPosition(b.position(), normalize(a.position() - b.position()), b.ps.uv))
        return false;
    return connect(scene, a, b, y.edge(i));
}

double walkDensity(const Scene &scene, const PathView &y, int l, int s, int end, const std::vector<double> &pFwd,
                   const std::vector<double> &pRev) {
    double density = 1.0;
    for (int i = l + 1; i <= l + s; ++i) density *= pFwd[static_cast<size_t>(i)] * importanceToCanonical(scene, y, i);
    for (int i = l + s + 1; i < end; ++i) density *= pRev[static_cast<size_t>(i)];
    return density;
}

}  // namespace pf
