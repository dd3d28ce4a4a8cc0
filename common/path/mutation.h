// Mutations of Veach's path-space Metropolis light transport (Veach & Guibas 1997; Veach 1997 ch. 11;
// ALGORITHMS.md §4): random changes of a complete path x into a proposal y, each with the density
// T(x -> y) that the Metropolis-Hastings acceptance needs (ALGORITHMS.md §2.1, mcmc/metropolis.h).
//
// The measure. Densities of paths with ideal specular vertices are pseudo-densities: the path-space layer
// measures a Dirac vertex's successor by the lobe's discrete probability times the cosine over the squared
// distance (path/vertex.h), and f uses the matching discrete BSDF weight. Such a measure is that of the walk
// that crosses the vertex, and the two walks disagree at Dirac refractions (path/path.h: contribution()).
// A Markov chain needs one measure for every state, so chains use the canonical one: f evaluated as the
// sensor walk evaluates it (chainContribution), and every T expressed in it. A mutation that creates a
// Dirac vertex with the emitter walk converts its density with importanceToCanonical(): the ratio of
// the vertex's two terms of f is the ratio of the two measures there, since f dmu is the same measure of
// light transport whichever walk describes it. f(y) / T(x -> y) is then the same weight that a walk
// computes (Veach 1997 ch. 11 writes the acceptance with these weights), whatever measure the walk used.
//
// Mutations are selected per step with probability proportional to their applicability (Veach 1997
// §11.4; Mitsuba calls it suitability), which depends on the state, so MutationSet folds the selection
// probability of the chosen type into T (ALGORITHMS.md §2.1, mixtures).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "mcmc/metropolis.h"
#include "path/path.h"
#include "scene/shape.h"

namespace pf {

// A complete path x_0 .. x_{n-1} (light order) that mutations edit. Unlike PathView it owns every vertex
// and also the two stateless edges to the supernodes, so that a mutation can splice any range.
class MutablePath final : public PathView {
public:
    MutablePath() { publish(); }
    explicit MutablePath(const PathView &view);
    MutablePath(const MutablePath &other) : PathView(other), vertices_(other.vertices_), edges_(other.edges_) {
        publish();
    }
    MutablePath(MutablePath &&other) noexcept
        : PathView(other), vertices_(std::move(other.vertices_)), edges_(std::move(other.edges_)) {
        publish();
        other.publish();
    }
    MutablePath &operator=(const MutablePath &other);
    MutablePath &operator=(MutablePath &&other) noexcept;
    using PathView::edge;
    using PathView::vertex;
    // Vertices -1 .. n and edges -1 .. n - 1 (edge i joins vertex i and vertex i + 1).
    PathVertex &vertex(int i) { return vertices_[static_cast<size_t>(i + 1)]; }
    PathEdge &edge(int i) { return edges_[static_cast<size_t>(i + 1)]; }
    // Where the path meets the film (the sensor node's raster position).
    const Vec2 &raster() const { return vertex(length() - 1).ps.uv; }
    // This path becomes x_{-1} .. x_l, `added` vertices to be filled in, x_m .. x_n, with the edges of
    // the two kept parts; the `added` + 1 edges between vertex l and vertex l + added + 1 are cleared.
    void splice(const MutablePath &x, int l, int m, int added);

private:
    // Publishes the vectors' storage to PathView; after every change of their size or buffer.
    void publish();
    const PathVertex &gatheredVertex(int i) const override { return vertices_[static_cast<size_t>(i + 1)]; }
    const PathEdge &gatheredEdge(int i) const override { return edges_[static_cast<size_t>(i + 1)]; }

    std::vector<PathVertex> vertices_;
    std::vector<PathEdge> edges_;
};

// The measurement contribution f in the canonical measure (see above): every vertex evaluated as the
// sensor walk evaluates it.
Spectrum chainContribution(const Scene &scene, const PathView &path);

// f_canonical / f_emitter-walk at vertex i: 1 unless the vertex is a Dirac refraction (see above).
double importanceToCanonical(const Scene &scene, const PathView &path, int i);

// Veach's non-specular vertex: one that a connection may end at (PathVertex::isConnectable) and that
// scatters through a smooth lobe, or the endpoint node it is. Inline and by type rather than through
// isConnectable(): chains classify every vertex many times per step (issue 17).
inline bool isNonSpecular(const PathVertex &v) {
    if (v.delta) return false;
    switch (v.type) {
        case VertexType::Surface:
            return (v.its.bsdf()->flags() & BSDFFlags::Smooth) != 0;
        case VertexType::EmitterNode:
            return !v.hasDeltaDirection();
        case VertexType::SensorNode:
        case VertexType::Medium:
            return true;
        default:
            return false;
    }
}

// Veach's mutation and perturbation types, manifold exploration's manifold perturbation
// (path/manifold_perturbation.h), its medium-distance perturbation (path/medium_distance_perturbation.h) and the
// portal perturbation (path/portal_perturbation.h), in the order of MutationSet's counts.
enum class MutationType { Bidirectional, LensSubpath, Lens, Caustic, MultiChain, Manifold, MediumDistance, Portal };
constexpr int kMutationTypes = 8;
const char *mutationName(MutationType type);

// What a mutation replaced: x keeps x_{-1} .. x_l and x_m .. x_n, and y has `added` new vertices between
// them (so y's kept suffix starts at l + added + 1). Perturbations replace x_{l+1} .. x_{m-1} in place.
struct MutationRecord {
    int l = 0, m = 0, added = 0;
    // Perturbations that can run either way over x_l .. x_m (the manifold perturbation): the vertex whose
    // direction was perturbed, l or m, or the supernode (-1 or n) whose endpoint node's position was offset
    // (the endpoint position perturbation, §6.5); unused by the others.
    int source = -1;
    // The manifold perturbation: the vertex that moved freely (x_b of ALGORITHMS.md §6.5), which its random
    // classification of glossy vertices chose (§6.6); -1 for the other mutations.
    int moving = -1;
    // The same move seen from y back to x.
    MutationRecord reverse() const { return {l, l + added + 1, m - l - 1, source, moving}; }
};

class Mutation {
public:
    virtual ~Mutation() = default;
    virtual MutationType type() const = 0;
    // Whether the mutation can be applied to x at all (Veach's applicability; Mitsuba's suitability).
    virtual bool applies(const PathView &x) const = 0;
    // Draws y ~ T(x -> .). Returns false when no proposal comes out (the walk left the scene, the
    // configuration changed, a connection is blocked): the chain then stays at x.
    virtual bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                        MutationRecord &record) const = 0;
    // T(x -> y) in the canonical measure for the move `record` (zero when the mutation cannot make it).
    virtual double density(const Scene &scene, const PathView &x, const PathView &y,
                           const MutationRecord &record) const = 0;
    // Adds what the mutation measured over a chain's run beyond proposals and acceptances (the manifold
    // walks of ALGORITHMS.md §5.5 Table 1) into `counters`.
    virtual void addCounters(ChainCounters &) const {}
};

// The mixture of enabled mutations: each is selected with probability proportional to its weight among
// those that apply (the portal perturbation's paper mixes them unequally, path/portal_perturbation.h).
class MutationSet {
public:
    // At most 64 mutations (applicable()'s mask).
    void add(std::unique_ptr<Mutation> mutation, double weight = 1.0) {
        mutations_.push_back(std::move(mutation));
        weights_.push_back(weight);
    }
    bool empty() const { return mutations_.empty(); }
    size_t size() const { return mutations_.size(); }
    const Mutation &operator[](size_t k) const { return *mutations_[k]; }
    // The mutations that apply to x, as a mask with bit k for mutation k. A chain keeps the mask with its
    // state: applicability walks the path, and each step needs it of x and of y (issue 17).
    uint64_t applicable(const PathView &x) const;
    // Probability that the step from a state whose applicable mutations are `mask` selects mutation k.
    double selectionProbability(uint64_t mask, size_t k) const;
    double selectionProbability(const PathView &x, size_t k) const { return selectionProbability(applicable(x), k); }
    // The mutation a uniform number u selects among `mask`, or -1 when none applies.
    int select(uint64_t mask, double u) const;
    int select(const PathView &x, double u) const { return select(applicable(x), u); }

private:
    std::vector<std::unique_ptr<Mutation>> mutations_;
    std::vector<double> weights_;
};

// Building blocks shared by the mutations that regenerate a subpath with the random walks of BDPT.

// Continues a random walk of `mode` from y's vertex `from` for `steps` new vertices, the way BDPT's walks
// sample them (SAMPLENEXT, no Russian roulette): the emitter walk towards higher indices, the sensor walk
// towards lower ones. The vertex before `from` in the walk is its neighbour on the other side; a supernode
// starts a new walk, and the sensor node draws its raster position uniformly over the film first. Fills
// the vertices and edges it reaches; false when the walk ends early.
bool extendWalk(const Scene &scene, Sampler &sampler, TransportMode mode, MutablePath &y, int from, int steps);

// CONNECT ([TH A4]) y's vertices i and i + 1 into a complete path: both become smooth vertices of it, a
// sensor node gets the raster position the connection enters the film at, and i = -1 casts vertex 0 to
// an emitter node. Returns false when there is no throughput (blocked, off the film, not smooth).
bool connectJunction(const Scene &scene, MutablePath &y, int i);
// Whether the edge between y's vertices i and i + 1 could have been such a connection (i = -1: vertex 0
// is an emitter node that a walk can hit).
bool isJunction(const PathView &y, int i);

// The density, in the canonical measure, with which the emitter walk from vertex l creates y's vertices
// l + 1 .. l + s and the sensor walk from vertex `end` creates l + s + 1 .. end - 1 (extendWalk), from
// evalDensities' p-> and p<- of y. Vertices the emitter walk creates are converted to the canonical measure.
double walkDensity(const Scene &scene, const PathView &y, int l, int s, int end, const std::vector<double> &pFwd,
                   const std::vector<double> &pRev);

}  // namespace pf
