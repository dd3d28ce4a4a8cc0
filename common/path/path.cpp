#include "path/path.h"

#include <algorithm>

#include "emitter/emitter.h"
#include "scene/scene.h"

namespace pf {

namespace {

// The edge between a supernode and its node carries nothing ([TH A4]: "stateless").
const PathEdge kStatelessEdge{};

// Whether a connection can end at v: its scattering or emission has a smooth part. The junction copies
// are smooth vertices of the joined path whatever lobe the walk itself left through. An emitter node on
// the sensor side is the environment that ended a sensor walk: only s = 0 uses it.
bool smoothAt(const PathVertex &v, TransportMode side) {
    if (v.isEndpointNode())
        return (v.type == VertexType::EmitterNode) == (side == TransportMode::Importance) && !v.hasDeltaDirection();
    return v.type == VertexType::Medium || (v.its.bsdf()->flags() & BSDFFlags::Smooth) != 0;
}

}  // namespace

void Path::sample(const Scene &scene, Sampler &sampler, TransportMode mode, int maxVertices, int rrDepth,
                  const Vec2 &raster) {
    mode_ = mode;
    vertices_.clear();
    edges_.clear();
    lensHits_.clear();
    endpointDirect_ = -1;
    // Room for typical walks up front: growing a vector of vertices one at a time shows in profiles.
    constexpr size_t kTypicalVertices = 16;
    vertices_.reserve(kTypicalVertices);
    edges_.reserve(kTypicalVertices);
    vertices_.push_back(mode == TransportMode::Importance ? PathVertex::emitterSupernode()
                                                          : PathVertex::sensorSupernode());
    PathVertex node;
    PathEdge unused;
    if (maxVertices == 0 || !vertices_[0].sampleNext(scene, sampler, mode, nullptr, unused, node)) return;
    if (mode == TransportMode::Radiance) node.ps.uv = raster;
    vertices_.push_back(node);

    const Spectrum start = node.throughput;
    const bool lens = mode == TransportMode::Importance && !scene.sensor().deltaAperture();
    const int reverse = modeIndex(otherMode(mode));
    // Edges so far plus the index-matched surfaces they crossed: the walk's depth in Mitsuba's count.
    int depth = 0;
    for (int k = 0; maxVertices < 0 || depth + 1 < maxVertices; ++k) {
        // Russian roulette on the throughput gathered since the endpoint, before the walk's edge rrDepth
        // (depth rrDepth - 1 so far), as Mitsuba's bidirectional walks start it (libbidir/path.cpp,
        // alternatingRandomWalkFromPixel: the sensor walk's vertex count t >= rrDepth, the emitter walk's
        // step s >= rrDepth), never before the first edge. The survival probability divides the next
        // vertex's throughput; MIS ignores it (Veach 1997 §10.3.3), which keeps the weights summing to one.
        double survival = 1.0;
        if (depth >= 1 && depth + 1 >= rrDepth) {
            survival = std::min((vertices_.back().throughput / start).max(), 0.95);
            if (sampler.next1D() >= survival) break;
        }
        const size_t cur = vertices_.size() - 1;
        PathEdge edge;
        // The successor is sampled in place (a copy of every vertex into the walk showed in profiles) and
        // dropped again if the walk ends before it.
        PathVertex &succ = vertices_.emplace_back();
        const bool sampled = vertices_[cur].sampleNext(scene, sampler, mode, &vertices_[cur - 1], edge, succ);
        if (lens && !edge.d.isZero()) recordLensHit(scene, k, edge, survival);
        depth += 1 + edge.crossings;
        // A vertex beyond maxDepth belongs to no path that may contribute (its prefix is already too deep).
        if (!sampled || (maxVertices >= 0 && depth + 1 > maxVertices)) {
            vertices_.pop_back();
            break;
        }
        succ.throughput *= 1.0 / survival;
        if (k >= 1)
            vertices_[cur - 1].pdf[reverse] = vertices_[cur].evalPdf(
                scene, &succ, vertices_[cur - 1], edges_[static_cast<size_t>(k - 1)], otherMode(mode));
        edges_.push_back(edge);
        if (succ.isEndpointNode()) break;  // the sensor walk reached the environment's sphere: it ends there
    }
}

void Path::recordLensHit(const Scene &scene, int from, const PathEdge &edge, double survival) {
    const Sensor &sensor = scene.sensor();
    const PathVertex &v = vertex(from), &pred = vertex(from - 1);
    PositionSample ps;
    double t = 0;
    if (!sensor.intersectAperture(Ray(v.position(), edge.d, 0.0, edge.length), ps, t)) return;
    LensHit hit;
    hit.from = from;
    hit.vertex = PathVertex::endpointNode(scene, ps, nullptr);
    hit.vertex.walkMode = TransportMode::Importance;
    if (!connect(scene, v, hit.vertex, hit.edge)) return;
    const double pdf = v.evalPdf(scene, &pred, hit.vertex, hit.edge, TransportMode::Importance);
    if (!(pdf > 0)) return;
    hit.vertex.pdf[modeIndex(TransportMode::Importance)] = pdf;
    hit.vertex.pdf[modeIndex(TransportMode::Radiance)] =
        PathVertex::sensorSupernode().evalPdf(scene, nullptr, hit.vertex, kStatelessEdge, TransportMode::Radiance);
    // The lens point is a sampled successor like any other: f over p for the sampled direction.
    hit.vertex.throughput = v.throughput * v.eval(scene, &pred, hit.vertex, TransportMode::Importance) *
                            edgeTerm(v, hit.vertex, hit.edge) * hit.vertex.cosine(edge.d) / (pdf * survival);
    if (!hit.vertex.throughput.isBlack()) lensHits_.push_back(hit);
}

double Path::endpointDirectDensity(const Scene &scene) const {
    if (endpointDirect_ < 0) endpointDirect_ = directDensity(scene, vertex(0), vertex(1));
    return endpointDirect_;
}

int pathDepth(const PathView &path) {
    int depth = path.length() - 1;
    for (int i = 0; i + 1 < path.length(); ++i) depth += path.edge(i).crossings;
    return depth;
}

void JoinedPath::reset(const Path *light, int a, const Path *camera, int b, int s) {
    light_ = light;
    camera_ = camera;
    a_ = a;
    b_ = b;
    publish(nullptr, nullptr, a + b);
    s_ = s;
    ownLightEnd_ = ownCameraEnd_ = false;
    junction_ = PathEdge();
    value_ = Spectrum(0.0);
    directEmitter_ = directSensor_ = -1;
}

void JoinedPath::setEnd(bool lightSide, const PathVertex &v, bool copy) {
    bool &own = lightSide ? ownLightEnd_ : ownCameraEnd_;
    own = copy || v.delta;
    if (!own) return;
    PathVertex &end = lightSide ? lightEnd_ : cameraEnd_;
    end = v;
    end.delta = false;
}

bool JoinedPath::connect(const Scene &scene, const Path &light, int s, const Path &camera, int t) {
    reset(&light, s, &camera, t, s);
    const PathVertex &l = light.vertex(s - 1), &c = camera.vertex(t - 1);
    if (!smoothAt(l, TransportMode::Importance) || !smoothAt(c, TransportMode::Radiance)) return false;
    setEnd(true, l, false);
    setEnd(false, c, t == 1);  // light tracing sets the sensor node's raster position
    return finishConnection(scene);
}

bool JoinedPath::connectDirectEmitter(const Scene &scene, const Vec2 &u, const Path &camera, int t) {
    reset(nullptr, 1, &camera, t, 1);
    const PathVertex &c = camera.vertex(t - 1);
    if (!smoothAt(c, TransportMode::Radiance)) return false;
    setEnd(false, c, false);
    DirectSample ds(c.position(), c.type == VertexType::Surface ? c.its.n : Vec3());
    scene.sampleEmitterDirect(ds, u);
    if (!(ds.pdf > 0) || !ds.object) return false;
    const auto *emitter = static_cast<const Emitter *>(ds.object);
    PositionSample ps;
    ps.p = ds.p;
    ps.n = ds.n;
    ps.uv = ds.uv;
    ps.measure = (emitter->flags() & EmitterFlags::DeltaPosition) ? Measure::Discrete : Measure::Area;
    lightEnd_ = PathVertex::endpointNode(scene, ps, emitter);
    lightEnd_.walkMode = TransportMode::Importance;
    ownLightEnd_ = true;
    const PathVertex &supernode = PathVertex::emitterSupernode();
    lightEnd_.pdf[modeIndex(TransportMode::Importance)] =
        supernode.evalPdf(scene, nullptr, lightEnd_, kStatelessEdge, TransportMode::Importance);
    const double density = directDensity(scene, lightEnd_, c);
    if (!(density > 0)) return false;
    lightEnd_.throughput = supernode.eval(scene, nullptr, lightEnd_, TransportMode::Importance) / density;
    directEmitter_ = density;
    return finishConnection(scene);
}

bool JoinedPath::connectDirectSensor(const Scene &scene, const Vec2 &u, const Path &light, int s) {
    reset(&light, s, nullptr, 1, s);
    const PathVertex &l = light.vertex(s - 1);
    if (!smoothAt(l, TransportMode::Importance)) return false;
    setEnd(true, l, false);
    const Sensor &sensor = scene.sensor();
    DirectSample ds(l.position(), l.type == VertexType::Surface ? l.its.n : Vec3());
    sensor.sampleDirect(ds, u);
    if (!(ds.pdf > 0)) return false;
    PositionSample ps;
    ps.p = ds.p;
    ps.n = ds.n;
    ps.uv = ds.uv;
    ps.measure = sensor.deltaAperture() ? Measure::Discrete : Measure::Area;
    cameraEnd_ = PathVertex::endpointNode(scene, ps, nullptr);
    ownCameraEnd_ = true;
    const PathVertex &supernode = PathVertex::sensorSupernode();
    cameraEnd_.pdf[modeIndex(TransportMode::Radiance)] =
        supernode.evalPdf(scene, nullptr, cameraEnd_, kStatelessEdge, TransportMode::Radiance);
    const double density = directDensity(scene, cameraEnd_, l);
    if (!(density > 0)) return false;
    cameraEnd_.throughput = supernode.eval(scene, nullptr, cameraEnd_, TransportMode::Radiance) / density;
    directSensor_ = density;
    return finishConnection(scene);
}

bool JoinedPath::finishConnection(const Scene &scene) {
    const PathVertex &lightEnd = vertex(a_ - 1), &cameraEnd = vertex(a_);
    // Light tracing lands wherever the connection enters the sensor (b = 1: the sensor node is a copy). A sensor
    // node sampled towards the light end (connectDirectSensor, which has set directSensor_) holds that raster
    // position already.
    if (b_ == 1 && directSensor_ < 0 &&
        !scene.sensor().rasterPosition(cameraEnd.position(), normalize(lightEnd.position() - cameraEnd.position()),
                                       cameraEnd_.ps.uv))
        return false;
    const PathVertex &lightPred = vertex(a_ - 2), &cameraPred = vertex(a_ + 1);
    const PathVertex::ConnectionTerms light =
        lightEnd.evalConnection(scene, &lightPred, cameraEnd, TransportMode::Importance);
    if (light.f.isBlack()) return false;
    const PathVertex::ConnectionTerms camera =
        cameraEnd.evalConnection(scene, &cameraPred, lightEnd, TransportMode::Radiance);
    if (camera.f.isBlack() || !pf::connect(scene, lightEnd, cameraEnd, junction_)) return false;
    value_ = lightEnd.throughput * light.f * edgeTerm(lightEnd, cameraEnd, junction_) * camera.f * cameraEnd.throughput;
    pRevJunction_[0] = cameraEnd.areaDensity(camera.toSucc, lightEnd, junction_, TransportMode::Radiance);
    pFwdJunction_[0] = lightEnd.areaDensity(light.toSucc, cameraEnd, junction_, TransportMode::Importance);
    if (a_ >= 2)
        pRevJunction_[1] = lightEnd.areaDensity(light.toPred, lightPred, edge(a_ - 2), TransportMode::Radiance);
    if (b_ >= 2)
        pFwdJunction_[1] = cameraEnd.areaDensity(camera.toPred, cameraPred, edge(a_), TransportMode::Importance);
    return !value_.isBlack();
}

void JoinedPath::evalJunctionDensities(const Scene &scene) {
    const int a = a_;
    pRevJunction_[0] = vertex(a).evalPdf(scene, &vertex(a + 1), vertex(a - 1), edge(a - 1), TransportMode::Radiance);
    pFwdJunction_[0] = vertex(a - 1).evalPdf(scene, &vertex(a - 2), vertex(a), edge(a - 1), TransportMode::Importance);
    if (a >= 2)
        pRevJunction_[1] =
            vertex(a - 1).evalPdf(scene, &vertex(a), vertex(a - 2), edge(a - 2), TransportMode::Radiance);
    if (b_ >= 2)
        pFwdJunction_[1] = vertex(a).evalPdf(scene, &vertex(a - 1), vertex(a + 1), edge(a), TransportMode::Importance);
}

bool JoinedPath::hitEmitter(const Scene &scene, const Path &camera, int t) {
    reset(nullptr, 1, &camera, t - 1, 0);
    lightEnd_ = camera.vertex(t - 1);
    ownLightEnd_ = true;
    if (!lightEnd_.cast(scene, VertexType::EmitterNode)) return false;
    junction_ = camera.edge(t - 2);
    const PathVertex &supernode = PathVertex::emitterSupernode();
    lightEnd_.pdf[modeIndex(TransportMode::Importance)] =
        supernode.evalPdf(scene, nullptr, lightEnd_, kStatelessEdge, TransportMode::Importance);
    value_ = lightEnd_.throughput * lightEnd_.eval(scene, &vertex(1), supernode, TransportMode::Radiance) *
             supernode.eval(scene, &lightEnd_, supernode, TransportMode::Radiance);
    if (value_.isBlack()) return false;
    evalJunctionDensities(scene);
    return true;
}

bool JoinedPath::hitLens(const Scene &scene, const Path &light, const LensHit &hit) {
    reset(&light, hit.from + 1, nullptr, 1, hit.from + 2);
    cameraEnd_ = hit.vertex;
    ownCameraEnd_ = true;
    junction_ = hit.edge;
    const PathVertex &supernode = PathVertex::sensorSupernode();
    value_ = cameraEnd_.throughput *
             cameraEnd_.eval(scene, &light.vertex(hit.from), supernode, TransportMode::Importance) *
             supernode.eval(scene, &cameraEnd_, supernode, TransportMode::Importance);
    if (value_.isBlack()) return false;
    evalJunctionDensities(scene);
    return true;
}

void JoinedPath::densities(const Scene &scene, bool sampleDirect, PathDensities &d) const {
    const int n = length(), a = a_, b = b_;
    const size_t size = static_cast<size_t>(n);
    d.pFwd.resize(size);
    d.pRev.resize(size);
    d.connectable.resize(size);
    const int imp = modeIndex(TransportMode::Importance), rad = modeIndex(TransportMode::Radiance);
    const auto put = [&](int i, const PathVertex &v) {
        const size_t k = static_cast<size_t>(i);
        d.pFwd[k] = v.pdf[imp];
        d.pRev[k] = v.pdf[rad];
        d.connectable[k] = v.isConnectable();
    };
    // The walks' vertices straight from the subpaths (x_i = light vertex i, x_{n-1-j} = sensor vertex j).
    for (int i = 0; i + 1 < a; ++i) put(i, light_->vertex(i));
    put(a - 1, ownLightEnd_ ? lightEnd_ : light_->vertex(a - 1));
    put(a, ownCameraEnd_ ? cameraEnd_ : camera_->vertex(b - 1));
    for (int j = b - 2; j >= 0; --j) put(n - 1 - j, camera_->vertex(j));
    d.pRev[static_cast<size_t>(a - 1)] = pRevJunction_[0];
    d.pFwd[static_cast<size_t>(a)] = pFwdJunction_[0];
    if (a >= 2) d.pRev[static_cast<size_t>(a - 2)] = pRevJunction_[1];
    if (b >= 2) d.pFwd[static_cast<size_t>(a + 1)] = pFwdJunction_[1];
    d.directEmitter = d.directSensor = 0;
    if (!sampleDirect || n < 3) return;
    d.directEmitter = directEmitter_ >= 0 ? directEmitter_
                      : a >= 2            ? light_->endpointDirectDensity(scene)
                                          : directDensity(scene, vertex(0), vertex(1));
    d.directSensor = directSensor_ >= 0 ? directSensor_
                     : b >= 2           ? camera_->endpointDirectDensity(scene)
                                        : directDensity(scene, vertex(n - 1), vertex(n - 2));
}

Spectrum contribution(const Scene &scene, const PathView &path, std::optional<TransportMode> mode) {
    ContributionTerms terms;
    terms.evaluate(scene, path, mode);
    return terms.product();
}

void ContributionTerms::resize(int n) {
    vertex_.resize(static_cast<size_t>(n));
    cosine_.resize(static_cast<size_t>(n));
    edge_.resize(static_cast<size_t>(std::max(n - 1, 0)));
}

void ContributionTerms::evaluateVertex(const Scene &scene, const PathView &path, int i,
                                       std::optional<TransportMode> mode) {
    const PathVertex &v = path.vertex(i);
    const TransportMode m = mode.value_or(v.walkMode);
    const int back = m == TransportMode::Importance ? -1 : 1;  // where the walk of m comes from
    const PathVertex &pred = path.vertex(i + back), &succ = path.vertex(i - back);
    vertex_[static_cast<size_t>(i)] = v.eval(scene, &pred, succ, m);
    cosine_[static_cast<size_t>(i)] = pred.isSupernode() ? 1.0 : v.cosine(normalize(pred.position() - v.position()));
}

void ContributionTerms::evaluateEdge(const PathView &path, int i) {
    edge_[static_cast<size_t>(i)] = edgeTerm(path.vertex(i), path.vertex(i + 1), path.edge(i));
}

void ContributionTerms::evaluate(const Scene &scene, const PathView &path, std::optional<TransportMode> mode) {
    const int n = path.length();
    resize(n);
    endpoints_ = PathVertex::emitterSupernode().eval(scene, nullptr, path.vertex(0), TransportMode::Importance) *
                 PathVertex::sensorSupernode().eval(scene, nullptr, path.vertex(n - 1), TransportMode::Radiance);
    for (int i = 0; i < n; ++i) evaluateVertex(scene, path, i, mode);
    for (int i = 0; i + 1 < n; ++i) evaluateEdge(path, i);
}

void ContributionTerms::update(const Scene &scene, const PathView &y, std::optional<TransportMode> mode,
                               const ContributionTerms &xTerms, int l, int m, int added) {
    const int n = y.length(), end = l + added + 1, shift = m - end;  // y's vertex j > end is x's j + shift
    resize(n);
    endpoints_ = PathVertex::emitterSupernode().eval(scene, nullptr, y.vertex(0), TransportMode::Importance) *
                 PathVertex::sensorSupernode().eval(scene, nullptr, y.vertex(n - 1), TransportMode::Radiance);
    for (int i = 0; i < n; ++i) {
        if (i >= l && i <= end) {
            evaluateVertex(scene, y, i, mode);
            continue;
        }
        const size_t from = static_cast<size_t>(i < l ? i : i + shift);
        vertex_[static_cast<size_t>(i)] = xTerms.vertex_[from];
        cosine_[static_cast<size_t>(i)] = xTerms.cosine_[from];
    }
    for (int i = 0; i + 1 < n; ++i) {
        if (i >= l && i < end) {
            evaluateEdge(y, i);
            continue;
        }
        edge_[static_cast<size_t>(i)] = xTerms.edge_[static_cast<size_t>(i < l ? i : i + shift)];
    }
}

Spectrum ContributionTerms::product() const {
    // In the order of the factors' definition (ALGORITHMS.md §1.1): the vertices, then the edges.
    Spectrum f = endpoints_;
    for (size_t i = 0; i < vertex_.size(); ++i) {
        f *= vertex_[i];
        f *= cosine_[i];
    }
    for (const Spectrum &e : edge_) f *= e;
    return f;
}

void evalDensities(const Scene &scene, const PathView &path, std::vector<double> &pFwd, std::vector<double> &pRev) {
    evalDensities(scene, path, 0, path.length() - 1, pFwd, pRev);
}

void evalDensities(const Scene &scene, const PathView &path, int first, int last, std::vector<double> &pFwd,
                   std::vector<double> &pRev) {
    const int n = path.length();
    pFwd.resize(static_cast<size_t>(n));
    pRev.resize(static_cast<size_t>(n));
    for (int i = std::max(first, 0); i <= std::min(last, n - 1); ++i) {
        // x_i as the emitter walk reaches it from x_{i-1} (x_{-1}: the supernode, which has no predecessor),
        // and as the sensor walk reaches it from x_{i+1}.
        const PathVertex *fromEmitter = i >= 1 ? &path.vertex(i - 2) : nullptr;
        const PathVertex *fromSensor = i + 1 < n ? &path.vertex(i + 2) : nullptr;
        pFwd[static_cast<size_t>(i)] = path.vertex(i - 1).evalPdf(
            scene, fromEmitter, path.vertex(i), i >= 1 ? path.edge(i - 1) : kStatelessEdge, TransportMode::Importance);
        pRev[static_cast<size_t>(i)] = path.vertex(i + 1).evalPdf(
            scene, fromSensor, path.vertex(i), i + 1 < n ? path.edge(i) : kStatelessEdge, TransportMode::Radiance);
    }
}

}  // namespace pf
