// Veach's bidirectional mutation (Veach & Guibas 1997; Veach 1997 ch. 11; ALGORITHMS.md §4.1-4.2):
// deletes a subpath x_{l+1} .. x_{m-1} and regenerates it, possibly with another number of vertices, by
// extending the kept prefix with s steps of the emitter walk and the kept suffix with t steps of the
// sensor walk and connecting the two (BDPT's building blocks). It changes the path's length and structure
// and gives the chain its ergodicity.
//
// Discrete choices, as in Mitsuba 0.6's implementation of Veach's scheme: the proposal's length n' from a
// two-tailed geometric distribution around n (ratio 1/2, within the allowed lengths), the number of deleted
// edges kd from one around 2 (at least 2 when n' = n, so that something changes, and enough to reach n'),
// the position l uniformly among those whose kept end vertices are non-specular and not points (a deletion
// that ends at a specular vertex or a pinhole could regenerate the same vertex: then several l would yield
// the same y), and the split s uniformly. Deleting one edge without adding a vertex, or the converse, never
// touches a supernode edge.
//
// T(x -> y) sums over every split s that yields the same y (§4.2): each one is a BDPT strategy of the new
// subpath, with its own density, and forgetting the others biases the result.
#pragma once
#include "path/mutation.h"

namespace pf {

class BidirectionalMutation final : public Mutation {
public:
    // Proposals have minVertices .. maxVertices vertices (maxVertices < 0: unbounded).
    BidirectionalMutation(int minVertices, int maxVertices);
    MutationType type() const override { return MutationType::Bidirectional; }
    bool applies(const PathView &) const override { return true; }
    bool sample(const Scene &scene, Sampler &sampler, const MutablePath &x, MutablePath &y,
                MutationRecord &record) const override;
    double density(const Scene &scene, const PathView &x, const PathView &y,
                   const MutationRecord &record) const override;

private:
    // The probability of the discrete choices that delete kd edges at l and add `added` vertices to x,
    // before the split.
    double choiceProbability(const PathView &x, int l, int kd, int added) const;
    // The positions l at which kd edges may be deleted from x when ka edges replace them, into `positions`
    // (a buffer the caller keeps: no allocation per step).
    void deletionPositions(const PathView &x, int kd, int ka, std::vector<int> &positions) const;

    int minVertices_, maxVertices_;
};

}  // namespace pf
