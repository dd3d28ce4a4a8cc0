// Path vertices of the path-space abstraction layer ([TH A4]; ALGORITHMS.md §1.1, §1.4). A path is
//
//     emitter supernode, emitter node x_0, x_1, ..., x_{n-1} sensor node, sensor supernode,
//
// with light flowing from x_0 to x_{n-1}. The supernodes are stateless: sampling a successor of one picks
// a position on an emitter or on the sensor's aperture, so that endpoint positions and directions are
// sampled (and later perturbed) separately. Interior vertices are surface or medium interactions.
//
// Every operation takes the transport mode of the walk it serves: Importance for the emitter walk
// (successors lie towards the sensor), Radiance for the sensor walk. Surface vertices then evaluate the
// adjoint BSDF (BSDFContext::mode) and, for importance, Veach's shading-normal correction, so that the
// vertex terms of f (ALGORITHMS.md §1.1) are the same whichever walk evaluates them (smooth lobes; Dirac
// weights differ by the solid-angle compression of refraction, see path.h). As in Mitsuba's bidirectional
// layer, f is zero where a direction lies on different sides of the shading and the geometric normal
// (the path tracer's strictNormals).
//
// Conventions of the vertex terms. eval() returns the part of f at a vertex together with the geometric
// cosine D (|N . w| on surfaces, 1 in media) towards its successor: f_s * D for a scattering vertex, the
// directional emission or importance profile (which contains the cosine) for an endpoint node leaving
// towards the path, and that profile divided by D for an endpoint node reached by the other walk
// (towards its supernode). A supernode's term is the spatial part of the emission or importance. The
// edge term is tau / d^2 (edge.h), so f is the product of all vertex and edge terms and of D at each
// vertex towards its predecessor (path.h: contribution()).
//
// Densities are in each vertex's own measure (area for surfaces and endpoints, volume in media, 1 for
// Dirac positions) and include the edge's free-flight probabilities (§1.4). A vertex sampled from a
// Dirac lobe (delta) has densities in the discrete measure of that lobe, and no connection can reach it.
#pragma once
#include <cstdint>

#include "bsdf/bsdf.h"
#include "core/sampler.h"
#include "core/spectrum.h"
#include "path/edge.h"
#include "scene/intersection.h"
#include "scene/records.h"

namespace pf {

class Emitter;
class Medium;
class Scene;

enum class VertexType : uint8_t { EmitterSupernode, SensorSupernode, EmitterNode, SensorNode, Surface, Medium };

struct PathVertex {
    VertexType type = VertexType::Surface;
    // Surfaces: the intersection. Endpoint nodes: p and n of the position sample, and the shape of an area
    // emitter (the whole intersection when cast from a surface). Medium vertices: p, with wi the world
    // direction towards the walk's predecessor (an identity shading frame).
    Intersection its;
    PositionSample ps;                 // endpoint nodes; sensor nodes keep their raster position in ps.uv
    const Emitter *emitter = nullptr;  // emitter nodes
    // Medium vertices: their medium. Surfaces: the medium the walk arrived through. Sensor nodes: the
    // sensor's medium.
    const Medium *medium = nullptr;
    bool delta = false;                                // the walk left this vertex through a Dirac lobe
    Vec3 woLocal;                                      // and in this direction (shading frame), see localDirections()
    TransportMode walkMode = TransportMode::Radiance;  // the walk that created the vertex
    double pdf[2] = {0.0, 0.0};                        // p<- and p-> ([modeIndex]), ALGORITHMS.md §1.4
    Spectrum throughput{0.0};                          // alpha: f / p of the subpath up to and including this vertex

    // The two stateless supernodes.
    static const PathVertex &emitterSupernode();
    static const PathVertex &sensorSupernode();
    // An endpoint node at a sampled position (emitter: pass the emitter; sensor: nullptr).
    static PathVertex endpointNode(const Scene &scene, const PositionSample &ps, const Emitter *emitter);

    const Vec3 &position() const { return its.p; }
    bool isSupernode() const { return type == VertexType::EmitterSupernode || type == VertexType::SensorSupernode; }
    bool isEndpointNode() const { return type == VertexType::EmitterNode || type == VertexType::SensorNode; }
    // A point light or a pinhole: no walk can reach it.
    bool hasDeltaPosition() const { return isEndpointNode() && ps.measure == Measure::Discrete; }
    // A beam of parallel light (directional emitter): it has no direction to connect to.
    bool hasDeltaDirection() const;
    // Whether a deterministic connection can end at this vertex (ALGORITHMS.md §1.4: not at delta vertices).
    bool isConnectable() const { return !isSupernode() && !delta && !hasDeltaDirection(); }
    // D: the cosine between the geometric normal and unit direction d (1 in media and at points).
    double cosine(const Vec3 &d) const;
    // The medium a ray leaving this vertex in direction d travels through.
    const Medium *mediumToward(const Vec3 &d) const;

    // SAMPLENEXT ([TH A4]): samples the edge leaving this vertex and the vertex at its end, given the
    // predecessor (nullptr for supernodes) in the walk of `mode`. Sets succ.pdf[mode], succ.throughput
    // (this vertex's throughput times the sampling weight) and, for surfaces, this vertex's delta flag.
    // edge.d is set whenever a direction was sampled, even if the ray then left the scene.
    // Consumes 3 numbers at the emitter supernode and at scattering vertices, 2 at the sensor supernode
    // and emitter nodes, none at sensor nodes (their direction is the raster position in ps.uv), plus
    // one per medium segment the edge crosses.
    bool sampleNext(const Scene &scene, Sampler &sampler, TransportMode mode, const PathVertex *pred, PathEdge &edge,
                    PathVertex &succ);
    // PERTURB ([TH A4]): replaces the successor by what the outgoing direction d (a unit vector) reaches:
    // traces the edge (sampling free flights in media) and builds succ's geometry. SampleNext calls it
    // with the sampled direction; Markov-chain perturbations call it with a perturbed one, then EVAL and
    // EVALPDF for the new terms.
    bool perturb(const Scene &scene, Sampler &sampler, TransportMode mode, const Vec3 &d, PathEdge &edge,
                 PathVertex &succ) const;
    // EVAL ([TH A4]): this vertex's term of f between pred and succ (see the conventions above); either
    // may be a supernode, pred is nullptr for a supernode.
    Spectrum eval(const Scene &scene, const PathVertex *pred, const PathVertex &succ, TransportMode mode) const;
    // EVALPDF ([TH A4]): the density, in succ's measure, with which sampleNext (with predecessor pred)
    // produces succ across `edge` in the walk of `mode`.
    double evalPdf(const Scene &scene, const PathVertex *pred, const PathVertex &succ, const PathEdge &edge,
                   TransportMode mode) const;
    // EVAL and both direction densities at the end of a connection (a vertex that is neither a supernode
    // nor delta), computed together so that a surface finds its local directions and sides once: see
    // ConnectionTerms. pred is its walk predecessor, succ the vertex across the connection.
    struct ConnectionTerms;
    ConnectionTerms evalConnection(const Scene &scene, const PathVertex *pred, const PathVertex &succ,
                                   TransportMode mode) const;
    // EVALPDF's last step: a direction density at this vertex (as directionPdf gives it) in succ's measure
    // across `edge`.
    double areaDensity(double pdfDir, const PathVertex &succ, const PathEdge &edge, TransportMode mode) const;
    // CAST ([TH A4]): reinterprets the vertex as `type`. A surface on an area emitter becomes an emitter
    // node (the end of a sensor walk that found an emitter), and such a node becomes the surface again.
    // Returns false (leaving the vertex unchanged) when the reinterpretation is impossible.
    bool cast(const Scene &scene, VertexType type);

private:
    // EVALPDF's density per solid angle (or discrete) of leaving towards succ, for an interior or endpoint
    // vertex.
    double directionPdf(const Scene &scene, const PathVertex *pred, const PathVertex &succ, TransportMode mode) const;
    // Local (shading-frame) directions towards pred and succ; Dirac vertices keep the directions they
    // were sampled with (see vertex.cpp). Returns whether both lie on the side where the geometric and the
    // shading normal agree (f is zero otherwise, see above).
    bool localDirections(const PathVertex &pred, const PathVertex &succ, TransportMode mode, Vec3 &wi, Vec3 &wo) const;
    // An endpoint node's direction towards `target`, in the measure its profile and density take.
    DirectionSample endpointDirection(const Vec3 &target) const;
    // An endpoint node's directional profile towards `target` (see eval), and with `pdf` directionPdf's density.
    Spectrum endpointProfile(const Scene &scene, const Vec3 &target, double *pdf = nullptr) const;
    Ray spawnRay(const Scene &scene, const Vec3 &d) const;
};

// What a connection needs at one of its ends: f = EVAL(pred, v, succ) in the walk's mode, and the
// direction densities of sampling succ from pred in that mode (toSucc) and pred from succ in the other
// (toPred; zero when pred is a supernode), which areaDensity turns into the p-> and p<- that the junction
// changes (ALGORITHMS.md §1.4).
struct PathVertex::ConnectionTerms {
    Spectrum f{0.0};
    double toSucc = 0, toPred = 0;
};

// CONNECT's visibility ([TH A4]): the edge from light-side vertex a to sensor-side vertex b, with
// transmittance and the densities of both walks; false if blocked.
bool connect(const Scene &scene, const PathVertex &a, const PathVertex &b, PathEdge &edge);

// The edge's share of f: tau / d^2, or tau next to a delta-direction endpoint, whose parallel beam does
// not spread.
Spectrum edgeTerm(const PathVertex &a, const PathVertex &b, const PathEdge &edge);

// The density, in the measure of endpoint node `node`, with which direct sampling from `ref` (next-event
// estimation towards an emitter, Scene::sampleEmitterDirect, or towards the sensor, Sensor::sampleDirect)
// produces it. BDPT's s = 1 and t = 1 strategies sample their endpoint this way (ALGORITHMS.md §1.4).
double directDensity(const Scene &scene, const PathVertex &node, const PathVertex &ref);

}  // namespace pf
