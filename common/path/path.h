// Subpaths and complete paths of the path-space layer ([TH A4]; ALGORITHMS.md §1.1, §1.4).
//
// A subpath is a random walk from one supernode: SAMPLENEXT until the walk ends (it leaves the scene, is
// absorbed, or Russian roulette stops it). A complete path x_0 .. x_{n-1} (light order) is seen through
// PathView: JoinedPath assembles one from the first s vertices of an emitter subpath and the first t of
// a sensor subpath, as the BDPT strategy (s, t) produces it, without copying the subpaths; MutablePath
// (path/mutation.h) holds a copy (for Markov chains that mutate paths, and for tests).
//
// Random numbers: a walk draws from its sampler in vertex order (vertex.h lists the count per vertex),
// so a subpath is a pure function of the sampler's stream and its first k vertices do not depend on
// how long the walk runs. Russian roulette draws one more number before each edge from edge rrDepth on.
//
// Depth, as Mitsuba 0.6 counts it for maxDepth and rrDepth: the edges of a path plus the index-matched
// surfaces they cross (edge.h), since Mitsuba's walks make a vertex of every such crossing
// (libbidir/path.cpp randomWalk; bdpt_proc.cpp bridges at most maxDepth - s - t + 1 of them in a
// connection).
#pragma once
#include <optional>
#include <vector>

#include "path/vertex.h"

namespace pf {

// The emitter walk crossing a finite lens (BDPT's t = 0 strategy). The lens is not part of the scene:
// the walk goes on behind it, and the lens point is kept as a second successor of vertex `from`.
struct LensHit {
    int from = 0;
    PathEdge edge;
    PathVertex vertex;
};

class Path {
public:
    // Samples a walk of `mode` (Importance: from the emitters; Radiance: from the sensor, through raster
    // position `raster`) with at most maxVertices vertices (-1: unbounded) besides the supernode, and
    // Russian roulette from its edge rrDepth on (as Mitsuba's bdpt), both counted with the crossings of index-matched
    // surfaces (a walk's depth + 1 vertices at most). The emitter walk records where it crosses a finite
    // lens. Along the way each vertex gets its reverse density (p of the other walk) as soon as its two
    // successors are known (ALGORITHMS.md §1.4).
    void sample(const Scene &scene, Sampler &sampler, TransportMode mode, int maxVertices, int rrDepth,
                const Vec2 &raster = {});

    TransportMode mode() const { return mode_; }
    int size() const { return static_cast<int>(vertices_.size()) - 1; }
    // Vertex i of the walk, 0 being the endpoint node; -1 is the supernode.
    const PathVertex &vertex(int i) const { return vertices_[static_cast<size_t>(i + 1)]; }
    // The edge between vertex(i) and vertex(i + 1), i >= 0.
    const PathEdge &edge(int i) const { return edges_[static_cast<size_t>(i)]; }
    const std::vector<LensHit> &lensHits() const { return lensHits_; }
    // directDensity of the endpoint node (vertex 0) from vertex 1 (size() >= 2): how the other walk's
    // direct sampling (BDPT's s = 1 or t = 1) would produce it. Every strategy that keeps both vertices
    // has it in its MIS weight, so it is computed once per walk, when first asked.
    double endpointDirectDensity(const Scene &scene) const;

private:
    void recordLensHit(const Scene &scene, int from, const PathEdge &edge, double survival);

    TransportMode mode_ = TransportMode::Radiance;
    std::vector<PathVertex> vertices_;
    std::vector<PathEdge> edges_;
    std::vector<LensHit> lensHits_;
    mutable double endpointDirect_ = -1;  // endpointDirectDensity once known
};

// What the MIS weights of a complete path's strategies depend on (mis.h): p->(x_i) and p<-(x_i), whether a
// connection can end at x_i, and the endpoint densities of direct sampling, directDensity of x_0 from x_1
// and of x_{n-1} from x_{n-2} (zero where they take no part: without sampleDirect, or for n < 3).
struct PathDensities {
    std::vector<double> pFwd, pRev;
    std::vector<char> connectable;
    double directEmitter = 0, directSensor = 0;
};

// A complete path x_0 .. x_{n-1} in light order; vertex(-1) and vertex(n) are the supernodes.
//
// A path that stores its vertices and edges contiguously (MutablePath, path/mutation.h) publishes them here, so
// that the path-space code reads them without a virtual call: Markov chains read every vertex many times per
// step through this interface, and the calls showed at 3% of a chains-only mlt profile (issue 17). A path
// assembled from two walks (JoinedPath) publishes nothing and answers through gatheredVertex/gatheredEdge.
class PathView {
public:
    virtual ~PathView() = default;
    int length() const { return length_; }
    const PathVertex &vertex(int i) const {
        return vertices_ ? vertices_[static_cast<ptrdiff_t>(i) + 1] : gatheredVertex(i);
    }
    // The edge between vertex(i) and vertex(i + 1), 0 <= i < length() - 1.
    const PathEdge &edge(int i) const { return edges_ ? edges_[i] : gatheredEdge(i); }

protected:
    PathView() = default;
    // A copy keeps the length but publishes no storage: a contiguous path publishes its own copy's (publish()).
    PathView(const PathView &other) : length_(other.length_) {}
    PathView &operator=(const PathView &other) {
        publish(nullptr, nullptr, other.length_);
        return *this;
    }
    // Vertex -1 and edge 0 of contiguous storage (nullptr: ask gatheredVertex/gatheredEdge), and the length.
    void publish(const PathVertex *vertexMinusOne, const PathEdge *edgeZero, int length) {
        vertices_ = vertexMinusOne;
        edges_ = edgeZero;
        length_ = length;
    }
    virtual const PathVertex &gatheredVertex(int i) const = 0;
    virtual const PathEdge &gatheredEdge(int i) const = 0;

private:
    const PathVertex *vertices_ = nullptr;
    const PathEdge *edges_ = nullptr;
    int length_ = 0;
};

// The path of one BDPT strategy (ALGORITHMS.md §0): s vertices from the emitter walk, t from the sensor
// walk. The builders return false when the strategy carries nothing for these subpaths (a Dirac vertex
// at the junction, an occluded or zero connection, a sample leaving the film).
class JoinedPath final : public PathView {
public:
    // CONNECT ([TH A4]) emitter vertex s - 1 with sensor vertex t - 1 (s, t >= 1). The junction vertices
    // are copied, so that the connection can update what it changes.
    bool connect(const Scene &scene, const Path &light, int s, const Path &camera, int t);
    // s = 1 with the emitter node sampled directly from sensor vertex t - 1 (two numbers u).
    bool connectDirectEmitter(const Scene &scene, const Vec2 &u, const Path &camera, int t);
    // t = 1 with the sensor node sampled directly from emitter vertex s - 1 (light tracing).
    bool connectDirectSensor(const Scene &scene, const Vec2 &u, const Path &light, int s);
    // s = 0: sensor vertex t - 1 lies on an emitter (CAST to an emitter node).
    bool hitEmitter(const Scene &scene, const Path &camera, int t);
    // t = 0: the emitter walk crossed the lens.
    bool hitLens(const Scene &scene, const Path &light, const LensHit &hit);

    // Inline: the connection and the MIS weights read the path's vertices many times per strategy.
    const PathVertex &vertex(int i) const {
        const int n = length();
        if (i < 0) return PathVertex::emitterSupernode();
        if (i >= n) return PathVertex::sensorSupernode();
        if (i < a_) return i == a_ - 1 && ownLightEnd_ ? lightEnd_ : light_->vertex(i);
        const int j = n - 1 - i;
        return j == b_ - 1 && ownCameraEnd_ ? cameraEnd_ : camera_->vertex(j);
    }
    const PathEdge &edge(int i) const {
        if (i < a_ - 1) return light_->edge(i);
        if (i == a_ - 1) return junction_;
        return camera_->edge(length() - 2 - i);
    }
    // s and t of the strategy that built the path.
    int lightVertices() const { return s_; }
    int sensorVertices() const { return length() - s_; }
    // f / p of the strategy that built the path (the unweighted BDPT contribution).
    const Spectrum &contribution() const { return value_; }
    // Where the path meets the film.
    const Vec2 &raster() const { return vertex(length() - 1).ps.uv; }
    // The densities of every vertex as BDPT keeps them (ALGORITHMS.md §1.4): those stored by the walks,
    // and the four that the junction changes, evaluated when the path was built. The direct densities
    // are those of the builder's own direct sample, or of the walks (Path::endpointDirectDensity).
    void densities(const Scene &scene, bool sampleDirect, PathDensities &d) const;

private:
    const PathVertex &gatheredVertex(int i) const override { return vertex(i); }
    const PathEdge &gatheredEdge(int i) const override { return edge(i); }
    void reset(const Path *light, int a, const Path *camera, int b, int s);
    // Makes walk vertex v the junction's light (or sensor) end. The junction's ends are smooth vertices of
    // the joined path: one that left its walk through a Dirac lobe is copied with that flag cleared, as is
    // one the connection changes (`copy`); the others are used in place, since copying every end showed
    // in profiles (issue 17).
    void setEnd(bool lightSide, const PathVertex &v, bool copy);
    // Completes a connection between lightEnd_ and cameraEnd_: visibility, the pixel for t = 1, f / p,
    // and the junction's densities.
    bool finishConnection(const Scene &scene);
    // The junction's densities with EVALPDF, for the paths that end at an emitter or the lens.
    void evalJunctionDensities(const Scene &scene);

    const Path *light_ = nullptr, *camera_ = nullptr;
    int a_ = 0, b_ = 0, s_ = 0;        // vertices taken from each side (including the ends below); strategy s
    PathVertex lightEnd_, cameraEnd_;  // replace light vertex a - 1 / sensor vertex b - 1 when owned
    bool ownLightEnd_ = false, ownCameraEnd_ = false;
    PathEdge junction_;  // between vertex(a - 1) and vertex(a)
    Spectrum value_;
    // What the junction changes: p<- of x_{a-1} and x_{a-2}, p-> of x_a and x_{a+1} (where they exist).
    double pRevJunction_[2] = {0, 0}, pFwdJunction_[2] = {0, 0};
    // directDensity of x_0 from x_1 and of x_{n-1} from x_{n-2} where a builder computed it; -1 otherwise.
    double directEmitter_ = -1, directSensor_ = -1;
};

// Mitsuba's depth of a complete path: its edges plus the index-matched surfaces they cross. maxDepth
// bounds it in every integrator.
int pathDepth(const PathView &path);

// The measurement contribution f(x) of ALGORITHMS.md §1.1 as the product of the EVAL terms, each vertex
// evaluated as the walk that sampled its successor evaluates it, or all in `mode`. The modes agree on
// every vertex except Dirac refractions: a discrete weight carries the solid-angle compression of the
// side it is measured from. Evaluated per walk, f / p_s is exactly the contribution that strategy s
// estimates, with the densities of evalDensities.
Spectrum contribution(const Scene &scene, const PathView &path, std::optional<TransportMode> mode = {});

// contribution()'s factors, kept one by one: a Markov chain whose mutation replaced a range of the path
// re-evaluates only the factors that depend on it and takes the others from the state it left (path_chain.h;
// issue 17). f is their product in contribution()'s order, so it has the same bits either way.
class ContributionTerms {
public:
    // Every factor of `path`, each vertex evaluated in `mode` or, without one, in its walk's mode.
    void evaluate(const Scene &scene, const PathView &path, std::optional<TransportMode> mode = {});
    // The factors of y, which is x with vertices l + 1 .. m - 1 replaced by `added` new ones (path/mutation.h:
    // MutationRecord): x's (`xTerms`) where y's vertex and its neighbours, or an edge's two ends, are x's,
    // that is below vertex l and edge l and beyond vertex and edge l + added + 1; the others evaluated on y.
    // A mutation keeps the positions of vertices l and l + added + 1 (it may change what else they hold).
    void update(const Scene &scene, const PathView &y, std::optional<TransportMode> mode,
                const ContributionTerms &xTerms, int l, int m, int added);
    Spectrum product() const;

private:
    void evaluateVertex(const Scene &scene, const PathView &path, int i, std::optional<TransportMode> mode);
    void evaluateEdge(const PathView &path, int i);
    void resize(int n);

    Spectrum endpoints_;            // the supernodes' terms
    std::vector<Spectrum> vertex_;  // EVAL at x_i in the walk's mode
    std::vector<double> cosine_;    // D at x_i towards the walk's predecessor (1 where that is a supernode)
    std::vector<Spectrum> edge_;    // edgeTerm of edge i
};

// EVALPDF at every vertex of the path: pFwd[i] = p->(x_i) from the emitter side, pRev[i] = p<-(x_i).
void evalDensities(const Scene &scene, const PathView &path, std::vector<double> &pFwd, std::vector<double> &pRev);
// The same at x_first .. x_last only (pFwd and pRev still get an entry per vertex; the others are left as they
// were): a mutation's density needs those of the vertices it created.
void evalDensities(const Scene &scene, const PathView &path, int first, int last, std::vector<double> &pFwd,
                   std::vector<double> &pRev);

}  // namespace pf
