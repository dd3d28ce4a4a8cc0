#include "path/vertex.h"

#include <memory>
#include <type_traits>

#include "emitter/emitter.h"
#include "integrators/visibility.h"
#include "scene/medium.h"
#include "scene/scene.h"

namespace pf {

namespace {

// Both directions on the side of the surface that the geometric and the shading normal agree on. Like
// Mitsuba's bidirectional layer, the path-space f is zero otherwise (strict normals: light leaking
// through a surface because of its shading normals is not light transport), which is what the path
// tracer computes with strictNormals.
bool sameSide(const Intersection &its, const Vec3 &wLocal) { return dot(its.toWorld(wLocal), its.n) * wLocal.z > 0; }
bool sidesAgree(const Intersection &its, const Vec3 &wiLocal, const Vec3 &woLocal) {
    return sameSide(its, wiLocal) && sameSide(its, woLocal);
}

}  // namespace

const PathVertex &PathVertex::emitterSupernode() {
    static const PathVertex v = [] {
        PathVertex s;
        s.type = VertexType::EmitterSupernode;
        s.walkMode = TransportMode::Importance;
        s.pdf[0] = s.pdf[1] = 1.0;
        return s;
    }();
    return v;
}

const PathVertex &PathVertex::sensorSupernode() {
    static const PathVertex v = [] {
        PathVertex s;
        s.type = VertexType::SensorSupernode;
        s.pdf[0] = s.pdf[1] = 1.0;
        return s;
    }();
    return v;
}

PathVertex PathVertex::endpointNode(const Scene &scene, const PositionSample &ps, const Emitter *emitter) {
    PathVertex v;
    v.type = emitter ? VertexType::EmitterNode : VertexType::SensorNode;
    v.ps = ps;
    v.emitter = emitter;
    v.its.p = ps.p;
    v.its.n = ps.n;
    v.its.uv = ps.uv;
    v.its.shape = emitter ? emitter->shape() : nullptr;
    v.medium = emitter ? nullptr : scene.sensor().medium();
    return v;
}

bool PathVertex::hasDeltaDirection() const {
    return type == VertexType::EmitterNode && (emitter->flags() & EmitterFlags::DeltaDirection) != 0;
}

double PathVertex::cosine(const Vec3 &d) const {
    switch (type) {
        case VertexType::Surface:
            return absDot(its.n, d);
        case VertexType::EmitterNode:
        case VertexType::SensorNode:
            return ps.n.isZero() ? 1.0 : absDot(ps.n, d);
        default:
            return 1.0;
    }
}

const Medium *PathVertex::mediumToward(const Vec3 &d) const {
    // Surfaces (and area emitters) that bound media switch to the medium on d's side.
    if (its.shape && (type == VertexType::Surface || type == VertexType::EmitterNode))
        return mediumAfter(its, d, medium);
    return medium;
}

Ray PathVertex::spawnRay(const Scene &scene, const Vec3 &d) const {
    if (its.shape && (type == VertexType::Surface || type == VertexType::EmitterNode)) return scene.spawnRay(its, d);
    if (type == VertexType::SensorNode) {
        const Sensor &sensor = scene.sensor();
        const double cosTheta = dot(sensor.forward(), d);
        return Ray(its.p, d, cosTheta > 0 ? sensor.nearClip() / cosTheta : kInfinity, kInfinity);
    }
    return Ray(its.p, d);
}

bool PathVertex::localDirections(const PathVertex &pred, const PathVertex &succ, TransportMode mode, Vec3 &wi,
                                 Vec3 &wo) const {
    if (delta) {
        // Rebuilt from positions, a direction is tilted by the offset of the ray origin (Scene::spawnRay)
        // by up to offset / distance, far more than a Dirac lobe's matching tolerance: keep the sampled
        // pair, in the order of the walk asking.
        const bool forward = mode == walkMode;
        wi = forward ? its.wi : woLocal;
        wo = forward ? woLocal : its.wi;
        return sidesAgree(its, wi, wo);
    }
    // The side test on the world directions themselves (sameSide without the round trip to the local frame).
    const Vec3 toPred = normalize(pred.position() - position()), toSucc = normalize(succ.position() - position());
    wi = its.toLocal(toPred);
    wo = its.toLocal(toSucc);
    return dot(toPred, its.n) * wi.z > 0 && dot(toSucc, its.n) * wo.z > 0;
}

DirectionSample PathVertex::endpointDirection(const Vec3 &target) const {
    DirectionSample ds;
    ds.d = normalize(target - position());
    ds.measure = hasDeltaDirection() ? Measure::Discrete : Measure::SolidAngle;
    return ds;
}

Spectrum PathVertex::endpointProfile(const Scene &scene, const Vec3 &target, double *pdf) const {
    const DirectionSample ds = endpointDirection(target);
    if (type == VertexType::EmitterNode) {
        if (pdf) *pdf = emitter->pdfDirection(ds, ps);
        return emitter->evalDirection(ds, ps);
    }
    const Sensor &sensor = scene.sensor();
    if (!sensor.beyondNearClip(target)) {
        if (pdf) *pdf = 0;
        return Spectrum(0.0);
    }
    return pdf ? sensor.evalDirectionAndPdf(ds, ps, *pdf) : sensor.evalDirection(ds, ps);
}

bool PathVertex::sampleNext(const Scene &scene, Sampler &sampler, TransportMode mode, const PathVertex *pred,
                            PathEdge &edge, PathVertex &succ) {
    edge = PathEdge();
    const int m = modeIndex(mode);
    if (type == VertexType::EmitterSupernode || type == VertexType::SensorSupernode) {
        const bool emitterSide = type == VertexType::EmitterSupernode;
        double pmf = 1.0;
        const Emitter *chosen = emitterSide ? scene.sampleEmitter(sampler.next1D(), pmf) : nullptr;
        const Vec2 u = sampler.next2D();
        if (emitterSide && !chosen) return false;
        PositionSample ps;
        const Spectrum weight = emitterSide ? chosen->samplePosition(ps, u) : scene.sensor().samplePosition(ps, u);
        succ = endpointNode(scene, ps, chosen);
        succ.walkMode = mode;
        succ.pdf[m] = evalPdf(scene, nullptr, succ, edge, mode);
        succ.throughput = weight / pmf;
        return !succ.throughput.isBlack();
    }

    Vec3 d;
    Spectrum weight;
    switch (type) {
        case VertexType::EmitterNode: {
            DirectionSample ds;
            weight = emitter->sampleDirection(ds, ps, sampler.next2D());
            d = ds.d;
            break;
        }
        case VertexType::SensorNode: {
            DirectionSample ds;
            PositionSample position = ps;
            weight = scene.sensor().sampleDirection(ds, position, ps.uv);
            d = ds.d;
            break;
        }
        case VertexType::Surface: {
            const double uLobe = sampler.next1D();
            const Vec2 u = sampler.next2D();
            if (!sameSide(its, its.wi)) return false;
            BSDFSample bs;
            weight = its.bsdf()->sample(BSDFContext(mode), its, its.wi, bs, uLobe, u);
            if (weight.isBlack() || !sameSide(its, bs.wo)) return false;
            d = its.toWorld(bs.wo);
            // Importance leaves through the sampled direction (the camera side): Veach's adjoint for
            // shading normals, with the camera-side direction first (bsdf.h).
            if (mode == TransportMode::Importance) weight *= shadingNormalCorrection(its, d, its.toWorld(its.wi));
            delta = (bs.sampledType & BSDFFlags::Delta) != 0;
            woLocal = bs.wo;
            break;
        }
        case VertexType::Medium: {
            // Scattering vertices draw three numbers each; a phase function needs only the last two.
            sampler.next1D();
            double pdfDir = 0;
            const double w = medium->phase().sample(its.wi, d, pdfDir, sampler.next2D());
            weight = medium->sigmaS() * w;
            break;
        }
        default:
            return false;
    }
    if (weight.isBlack()) return false;
    if (!perturb(scene, sampler, mode, d, edge, succ)) return false;
    const double pdf = evalPdf(scene, pred, succ, edge, mode);
    if (!(pdf > 0) || !(edge.pdf[m] > 0)) return false;
    succ.pdf[m] = pdf;
    succ.throughput = throughput * weight * edge.transmittance / edge.pdf[m];
    return !succ.throughput.isBlack();
}

bool PathVertex::perturb(const Scene &scene, Sampler &sampler, TransportMode mode, const Vec3 &d, PathEdge &edge,
                         PathVertex &succ) const {
    // A default vertex built in place (`succ = PathVertex()` cleared a 496-byte temporary and copied it over),
    // into which the walk writes the surface it reaches.
    static_assert(std::is_trivially_destructible_v<PathVertex>);
    std::construct_at(&succ);
    const EdgeEnd end = traceEdge(scene, sampler, spawnRay(scene, d), position(), mediumToward(d),
                                  type == VertexType::Medium, mode, edge, succ.its);
    edge.length = kInfinity;
    if (edge.transmittance.isBlack()) return false;
    switch (end.kind) {
        case EdgeEnd::Kind::Surface:
            break;
        case EdgeEnd::Kind::Medium:
            succ.its = Intersection();  // the walk may have met a surface beyond the interaction
            succ.type = VertexType::Medium;
            succ.its.p = end.p;
            succ.its.wi = -d;
            break;
        case EdgeEnd::Kind::Escaped: {
            // A sensor walk leaving the scene meets the sphere that stands in for the environment
            // (emitter/environment.h), an emitter node with an area density like any other.
            const Emitter *environment = scene.environment();
            DirectSample ds;
            if (mode != TransportMode::Radiance || !environment || !environment->fillDirectSample(ds, end.lastRay))
                return false;
            PositionSample ps;
            ps.p = ds.p;
            ps.n = ds.n;
            ps.uv = ds.uv;
            ps.measure = Measure::Area;
            succ = endpointNode(scene, ps, environment);
            break;
        }
    }
    if (!succ.isEndpointNode()) succ.medium = end.medium;
    succ.walkMode = mode;
    edge.length = (succ.position() - position()).length();
    return true;
}

Spectrum PathVertex::eval(const Scene &scene, const PathVertex *pred, const PathVertex &succ,
                          TransportMode mode) const {
    switch (type) {
        case VertexType::EmitterSupernode:
        case VertexType::SensorSupernode: {
            const PathVertex &node = succ.isEndpointNode() ? succ : *pred;
            return type == VertexType::EmitterSupernode ? node.emitter->evalPosition(node.ps)
                                                        : scene.sensor().evalPosition(node.ps);
        }
        case VertexType::EmitterNode:
        case VertexType::SensorNode: {
            // Leaving towards the path the profile holds the cosine; reached by the other walk (towards
            // the supernode), the cosine belongs to the edge just crossed (see vertex.h).
            if (!succ.isSupernode()) return endpointProfile(scene, succ.position());
            const double D = cosine(normalize(pred->position() - position()));
            return D > 0 ? endpointProfile(scene, pred->position()) / D : Spectrum(0.0);
        }
        case VertexType::Surface: {
            Vec3 wi, wo;
            if (!localDirections(*pred, succ, mode, wi, wo)) return Spectrum(0.0);
            Spectrum f =
                its.bsdf()->eval(BSDFContext(mode), its, wi, wo, delta ? Measure::Discrete : Measure::SolidAngle);
            if (mode == TransportMode::Importance) f *= shadingNormalCorrection(its, its.toWorld(wo), its.toWorld(wi));
            return f;
        }
        case VertexType::Medium:
            return medium->sigmaS() * medium->phase().eval(normalize(pred->position() - position()),
                                                           normalize(succ.position() - position()));
    }
    return Spectrum(0.0);
}

double PathVertex::evalPdf(const Scene &scene, const PathVertex *pred, const PathVertex &succ, const PathEdge &edge,
                           TransportMode mode) const {
    if (succ.isSupernode()) return 1.0;
    if (type == VertexType::EmitterSupernode)
        return scene.emitterPmf(succ.emitter) * succ.emitter->pdfPosition(succ.ps);
    if (type == VertexType::SensorSupernode) return scene.sensor().pdfPosition(succ.ps);
    // No walk reaches a point (point light, pinhole) or enters a parallel beam.
    if (succ.hasDeltaPosition() || succ.hasDeltaDirection()) return 0.0;
    return areaDensity(directionPdf(scene, pred, succ, mode), succ, edge, mode);
}

double PathVertex::directionPdf(const Scene &scene, const PathVertex *pred, const PathVertex &succ,
                                TransportMode mode) const {
    switch (type) {
        case VertexType::EmitterNode:
        case VertexType::SensorNode: {
            const DirectionSample ds = endpointDirection(succ.position());
            if (type == VertexType::EmitterNode) return emitter->pdfDirection(ds, ps);
            return scene.sensor().beyondNearClip(succ.position()) ? scene.sensor().pdfDirection(ds, ps) : 0.0;
        }
        case VertexType::Surface: {
            Vec3 wi, wo;
            if (!localDirections(*pred, succ, mode, wi, wo)) return 0.0;
            return its.bsdf()->pdf(BSDFContext(mode), its, wi, wo, delta ? Measure::Discrete : Measure::SolidAngle);
        }
        case VertexType::Medium:
            return medium->phase().pdf(normalize(pred->position() - position()),
                                       normalize(succ.position() - position()));
        default:
            return 0.0;
    }
}

double PathVertex::areaDensity(double pdfDir, const PathVertex &succ, const PathEdge &edge, TransportMode mode) const {
    if (succ.hasDeltaPosition() || succ.hasDeltaDirection()) return 0.0;
    const Vec3 toSucc = succ.position() - position();
    const double dist2 = toSucc.lengthSquared();
    const Vec3 d = toSucc / std::sqrt(dist2);
    // Solid angle to succ's measure: D at succ over d^2, except from a parallel beam, which does not spread.
    const double spread = hasDeltaDirection() ? 1.0 : 1.0 / dist2;
    return pdfDir * succ.cosine(d) * spread * edge.pdf[modeIndex(mode)];
}

PathVertex::ConnectionTerms PathVertex::evalConnection(const Scene &scene, const PathVertex *pred,
                                                       const PathVertex &succ, TransportMode mode) const {
    ConnectionTerms c;
    if (isEndpointNode() && pred->isSupernode()) {
        // eval's profile towards succ and directionPdf's density, from one direction and, for the lens, one
        // projection onto the film, where the two calls normalized and projected once each (issue 17).
        c.f = endpointProfile(scene, succ.position(), &c.toSucc);
        return c;
    }
    if (type != VertexType::Surface) {
        c.f = eval(scene, pred, succ, mode);
        if (c.f.isBlack()) return c;
        c.toSucc = directionPdf(scene, pred, succ, mode);
        if (!pred->isSupernode()) c.toPred = directionPdf(scene, &succ, *pred, otherMode(mode));
        return c;
    }
    // As eval and directionPdf compute them, with the local directions and the side test shared: the
    // reverse density swaps wi and wo (a connection's end is never delta, so both come from positions).
    Vec3 wi, wo;
    if (!localDirections(*pred, succ, mode, wi, wo)) return c;
    const BSDF *bsdf = its.bsdf();
    c.f = bsdf->eval(BSDFContext(mode), its, wi, wo, Measure::SolidAngle);
    if (c.f.isBlack()) return c;
    if (mode == TransportMode::Importance) c.f *= shadingNormalCorrection(its, its.toWorld(wo), its.toWorld(wi));
    c.toSucc = bsdf->pdf(BSDFContext(mode), its, wi, wo, Measure::SolidAngle);
    c.toPred = bsdf->pdf(BSDFContext(otherMode(mode)), its, wo, wi, Measure::SolidAngle);
    return c;
}

bool PathVertex::cast(const Scene &scene, VertexType to) {
    if (to == type) return true;
    if (type != VertexType::Surface || to != VertexType::EmitterNode || !its.emitter()) return false;
    type = VertexType::EmitterNode;
    emitter = its.emitter();
    ps.p = its.p;
    ps.n = its.n;
    ps.uv = its.uv;
    ps.shape = its.shape;
    ps.measure = Measure::Area;
    ps.pdf = emitter->pdfPosition(ps);
    delta = false;
    pdf[modeIndex(TransportMode::Importance)] = scene.emitterPmf(emitter) * ps.pdf;
    return true;
}

bool connect(const Scene &scene, const PathVertex &a, const PathVertex &b, PathEdge &edge) {
    const Vec3 &target = b.position();
    const bool onSurface = a.its.shape && (a.type == VertexType::Surface || a.type == VertexType::EmitterNode);
    Ray ray = onSurface ? scene.spawnRayTo(a.its, target) : scene.spawnRayTo(a.position(), target);
    if (b.type == VertexType::SensorNode) {
        const Sensor &sensor = scene.sensor();
        const double cosTheta = -dot(sensor.forward(), ray.d);
        if (!(cosTheta > 0)) return false;
        ray.tmax = std::min(ray.tmax, (target - ray.o).length() - sensor.nearClip() / cosTheta);
    }
    if (!(ray.tmax > ray.tmin)) return false;
    return connectEdge(scene, ray, a.position(), target, a.mediumToward(ray.d), a.type == VertexType::Medium,
                       b.type == VertexType::Medium, TransportMode::Importance, edge);
}

Spectrum edgeTerm(const PathVertex &a, const PathVertex &b, const PathEdge &edge) {
    if (a.hasDeltaDirection() || b.hasDeltaDirection()) return edge.transmittance;
    return edge.transmittance / (b.position() - a.position()).lengthSquared();
}

double directDensity(const Scene &scene, const PathVertex &node, const PathVertex &ref) {
    DirectSample ds(ref.position(), ref.type == VertexType::Surface ? ref.its.n : Vec3());
    const Vec3 toNode = node.position() - ref.position();
    ds.dist = toNode.length();
    ds.d = toNode / ds.dist;
    ds.p = node.position();
    ds.n = node.ps.n;
    ds.uv = node.ps.uv;
    const bool emitterSide = node.type == VertexType::EmitterNode;
    const Sensor &sensor = scene.sensor();
    const bool discrete = emitterSide ? node.emitter->isDelta() : sensor.deltaAperture();
    ds.measure = discrete ? Measure::Discrete : Measure::SolidAngle;
    ds.object = emitterSide ? static_cast<const Object *>(node.emitter) : &sensor;
    const double pdf = emitterSide ? scene.pdfEmitterDirect(ds, node.emitter) : sensor.pdfDirect(ds);
    // Solid angle at ref to area at the node; a Dirac choice stays discrete.
    return discrete ? pdf : pdf * node.cosine(ds.d) / (ds.dist * ds.dist);
}

}  // namespace pf
