// Detailed balance of Veach's mutations and perturbations (Veach 1997 ch. 11; ALGORITHMS.md §9.1.4, §9.4)
// on the shared scenes and Veach's swimming pool (and of the portal perturbation on the portal scenes,
// whose density test_portal checks against its sampler), for random current paths (BDPT's, and states that chains
// reach from them) and proposals drawn by each mutation:
//
// * the density each mutation reports is the density its sampler has: for proposals whose new vertices
//   are all non-specular (the canonical measure is then the area measure), T(x -> y) equals 1 / |det J|,
//   J the finite-difference Jacobian of the new vertices' surface coordinates with respect to the random
//   numbers the mutation drew;
// * every sampled proposal has T(x -> y) > 0, and the reverse move has T(y -> x) > 0 except where it is
//   structurally impossible (checked case by case below);
// * pi(x) T(x -> y) a(x -> y) = pi(y) T(y -> x) a(y -> x) with the core's acceptance, mixture selection
//   probabilities included;
// * the move changes the path only where its record says, so that f from x's factors outside that range
//   and y's inside it (ContributionTerms, as chains evaluate proposals) has the bits of f evaluated anew.
//
// The manifold perturbation (ALGORITHMS.md §6.5) gets the same checks, and where its chains are specular,
// the finite-difference check of the one vertex that moves freely: x'_m's area density from the direction
// kernel equals T(x -> y) converted back to the manifold measure with the chain's rho (manifold_perturbation.h),
// so the conversion through the generalized geometry term is checked against the sampler itself. With the
// glossy extension (ALGORITHMS.md §6.6) the same holds on offset manifolds (glossy-spheres: chains of rough
// glass and rough gold), where T also carries the classification probability and the offset Jacobian
// |∂x / ∂o| of the glossy chain vertices, which is checked on its own against finite differences of the
// offsets o = T^T h under moves of the glossy vertices on their surfaces.
//
// On volumetric-caustic-small, whose camera sees the gas through an index-matched front wall, proposals must also
// move chains across that boundary (the manifold perturbation at dtheta = 20 degrees, the medium-distance
// perturbation along the camera's edge), and every changed edge across it must carry the transmittance that a
// fresh connection gives. The image comparisons cannot see a wrong transmittance there: it changes f mostly with
// the depth along the camera ray, which moves energy along the ray, not between pixels (dropping the gas's
// transmittance on those edges left test_mept_media's worst |z| at 0.8-2.6; here it fails 19-57 edges).
//
// Whether the mutations keep the right stationary distribution as a whole is tested by rendering:
// test_erpt.cpp runs bursts with each perturbation alone against BDPT, test_mept.cpp MEPT and MEMLT.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "integrators/bdpt.h"
#include "mcmc/metropolis.h"
#include "path/bidirectional_mutation.h"
#include "path/caustic_perturbation.h"
#include "path/lens_perturbation.h"
#include "path/lens_subpath_mutation.h"
#include "path/manifold_perturbation.h"
#include "path/medium_distance_perturbation.h"
#include "path/multichain_perturbation.h"
#include "path/path_chain.h"
#include "path/portal_perturbation.h"
#include "render/image_task.h"
#include "scene/scene.h"
#include "test_mlt_common.h"
#include "test_path_helpers.h"

namespace pf::test {
namespace {

constexpr int kResolution = 16;
// dtheta of the glossy classification: the integrators' default of 1 degree (manifold_perturbation.h).
constexpr double kGlossyAngle = kPi / 180;

std::unique_ptr<Scene> testScene(const std::string &name) { return loadMLTTestScene(name, kResolution, 4); }

// Every mutation type, in MutationType order.
MutationSet allMutations(const Scene &scene, double glossyAngle = kGlossyAngle) {
    const PerturbationScale scale(scene);
    MutationSet set;
    set.add(std::make_unique<BidirectionalMutation>(2, maxVertices(scene)));
    set.add(std::make_unique<LensSubpathMutation>());
    set.add(std::make_unique<LensPerturbation>(scale));
    set.add(std::make_unique<CausticPerturbation>(scale));
    set.add(std::make_unique<MultiChainPerturbation>(scale));
    set.add(std::make_unique<ManifoldPerturbation>(scene, 50.0, glossyAngle));
    set.add(std::make_unique<MediumDistancePerturbation>());
    set.add(std::make_unique<PortalPerturbation>(scene, 1.0 / 256, 1.0 / 16));
    return set;
}

// Random current paths: BDPT's, as chains start from, each followed by the state a chain with every
// mutation reaches from it in a few steps (mutated paths hold vertices that no walk made).
std::vector<MutablePath> currentPaths(const Scene &scene, size_t count) {
    const MutationSet set = allMutations(scene);
    ImageBlock film = makeFilmBlock(scene);
    MutationCounts counts = PathChain::mutationTypes(
        {MutationType::Bidirectional, MutationType::LensSubpath, MutationType::Lens, MutationType::Caustic,
         MutationType::MultiChain, MutationType::Manifold, MutationType::MediumDistance, MutationType::Portal});
    PCG32 rng(5, 7);
    std::vector<MutablePath> paths;
    for (const MutablePath &x : bdptPaths(scene, count / 2, kResolution)) {
        paths.push_back(x);
        PathChain chain(scene, set, 2, maxVertices(scene), film, 1.0);
        chain.start(x);
        runMetropolis(chain, 10, rng, nullptr, counts);
        paths.push_back(chain.current());
    }
    return paths;
}

// Why the reverse of x -> y can be impossible although the forward move was made.
bool reverseStructurallyImpossible(const Scene &scene, const Mutation &mutation, const PathView &x, const PathView &y,
                                   const MutationRecord &record) {
    switch (mutation.type()) {
        case MutationType::Caustic: {
            // The angle range depends on the state: the reverse angle may lie outside y's range.
            const auto &caustic = static_cast<const CausticPerturbation &>(mutation);
            int a = x.length() - 3;
            while (!isNonSpecular(x.vertex(a))) --a;
            const Vec3 axis = rayDirection(scene, y.vertex(a), y.vertex(a + 1));
            const Vec3 back = rayDirection(scene, x.vertex(a), x.vertex(a + 1));
            const double theta = std::atan2(cross(axis, back).length(), dot(axis, back));
            const ReciprocalKernel k = caustic.angleKernel(y);
            return theta < k.lo() || theta > k.hi();
        }
        case MutationType::Bidirectional: {
            // A kept end vertex of y turned specular when the walk left it through a Dirac lobe, or no
            // split of x's deleted vertices ends at a possible connection.
            const int l = record.l, end = record.l + record.added + 1, n = x.length();
            const auto keepable = [](const PathVertex &v) { return isNonSpecular(v) && !v.hasDeltaPosition(); };
            if ((l >= 0 && !keepable(y.vertex(l))) || (end < y.length() && !keepable(y.vertex(end)))) return true;
            const int deleted = record.m - l - 1, lastSplit = record.m == n ? deleted - 1 : deleted;
            for (int s = 0; s <= lastSplit; ++s)
                if (isJunction(x, l + s)) return false;
            return true;
        }
        case MutationType::Portal: {
            // y crosses a portal first elsewhere: the reverse move would turn another edge (or about
            // another point).
            const PortalCrossing cx = firstPortalCrossing(scene, x), cy = firstPortalCrossing(scene, y);
            return cx.edge != cy.edge || cx.portal != cy.portal;
        }
        default:
            return false;
    }
}

struct BalanceCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const BalanceCase &c, std::ostream *os) { *os << c.scene << " " << mutationName(c.type); }
    std::string scene;
    MutationType type;
    // Proposals whose changed edges must cross an index-matched boundary (volumetric-caustic-small's front wall,
    // between the camera and the gas): chains across them (§6.7, path/manifold_perturbation.h).
    int minCrossing = 0;
    // dtheta of the classification; with a larger one medium vertices join chains more often (ManifoldChains).
    double glossyAngle = kGlossyAngle;
};

// The edges of y that cross index-matched boundaries within the range the move x -> y changed and whose
// transmittance differs from that of a fresh connection between their vertices (the medium on each side of every
// boundary crossed, edge.h): f would be wrong on them. A chain that kept the transmittance of one medium only
// would pass the balance check above, since f enters both of its sides.
int crossingEdgesUnlikeConnections(const Scene &scene, const PathView &y, const MutationRecord &record) {
    int mismatches = 0;
    for (int i = std::max(record.l, 0); i < std::min(record.m, y.length() - 1); ++i) {
        if (y.edge(i).crossings == 0) continue;
        PathEdge fresh;
        const double stored = y.edge(i).transmittance.luminance();
        // Traced and connected edges start from different ray offsets (Scene::spawnRay): up to 2e-5 relative
        // in the gas; one medium's transmittance missing changes it by e^{sigma_t t}, tens of percent.
        mismatches += !connect(scene, y.vertex(i), y.vertex(i + 1), fresh) ||
                      std::abs(fresh.transmittance.luminance() - stored) > 1e-3 * stored;
    }
    return mismatches;
}

// Whether the move x -> y (record) used an edge across an index-matched boundary that it could not use before
// chains crossed them: for the manifold perturbation, an edge of the walked second chain (x_b to x_c, more than
// a junction) or the held edge into a medium chain vertex of the first (x_a to x_b); for the medium-distance
// perturbation, the edge from the anchor along which the medium vertex moved.
bool crossesInChain(const PathView &y, const MutationRecord &record, MutationType type) {
    const auto crosses = [&](int a, int b) { return y.edge(std::min(a, b)).crossings > 0; };
    if (type == MutationType::MediumDistance) return crosses(record.moving, record.source);
    if (type != MutationType::Manifold || record.moving < 0) return false;
    const int fixed = record.source == record.l ? record.m : record.l, dir = fixed > record.moving ? 1 : -1;
    if (std::abs(fixed - record.moving) > 1)
        for (int i = record.moving; i != fixed; i += dir)
            if (crosses(i, i + dir)) return true;
    for (int i = record.moving; i != record.source; i -= dir)
        if (y.vertex(i).type == VertexType::Medium && i != record.moving && crosses(i, i - dir)) return true;
    return false;
}

class DetailedBalance : public ::testing::TestWithParam<BalanceCase> {};

TEST_P(DetailedBalance, HoldsForSampledProposals) {
    const BalanceCase &c = GetParam();
    auto scene = testScene(c.scene);
    const MutationSet set = allMutations(*scene, c.glossyAngle);
    const size_t k = static_cast<size_t>(c.type);
    const Mutation &mutation = set[k];
    const std::vector<MutablePath> paths = currentPaths(*scene, 3000);
    int applicable = 0, proposals = 0, symmetric = 0, impossibleReverse = 0, crossing = 0, unlike = 0;
    for (size_t i = 0; i < paths.size() && (proposals < 400 || crossing < c.minCrossing); ++i) {
        const MutablePath &x = paths[i];
        if (!mutation.applies(x)) continue;
        ++applicable;
        const double piX = chainContribution(*scene, x).luminance();
        for (uint64_t j = 0; j < 8; ++j) {
            IndependentSampler sampler(99, i, j);
            MutablePath y;
            MutationRecord record;
            if (!mutation.sample(*scene, sampler, x, y, record)) continue;
            const Spectrum fY = chainContribution(*scene, y);
            const double piY = fY.luminance();
            if (!(piY > 0)) continue;
            ++proposals;
            // A chain re-evaluates only the factors of f that the move changed, by its record (path_chain.h):
            // the move must leave the rest of the path as it was, and f comes out with the same bits.
            ContributionTerms xTerms, yTerms;
            xTerms.evaluate(*scene, x, TransportMode::Radiance);
            yTerms.update(*scene, y, TransportMode::Radiance, xTerms, record.l, record.m, record.added);
            const Spectrum kept = yTerms.product();
            EXPECT_TRUE(kept.r == fY.r && kept.g == fY.g && kept.b == fY.b)
                << "f from the kept factors differs: path " << i << " proposal " << j;
            crossing += crossesInChain(y, record, c.type);
            unlike += crossingEdgesUnlikeConnections(*scene, y, record);
            const double txy = set.selectionProbability(x, k) * mutation.density(*scene, x, y, record);
            const double tyx = set.selectionProbability(y, k) * mutation.density(*scene, y, x, record.reverse());

            ASSERT_GT(txy, 0.0) << "a sampled proposal must have positive density (path " << i << ")";
            ASSERT_TRUE(std::isfinite(txy) && std::isfinite(tyx));
            if (tyx > 0) {
                ++symmetric;
            } else {
                EXPECT_TRUE(reverseStructurallyImpossible(*scene, mutation, x, y, record))
                    << "asymmetric support: path " << i << " proposal " << j;
                ++impossibleReverse;
            }
            Proposal forward, backward;
            forward.target = piY, forward.forward = txy, forward.backward = tyx;
            backward.target = piX, backward.forward = tyx, backward.backward = txy;
            const double lhs = piX * txy * acceptance(piX, forward), rhs = piY * tyx * acceptance(piY, backward);
            EXPECT_NEAR(lhs, rhs, 1e-12 * std::max(lhs, rhs)) << "path " << i << " proposal " << j;
        }
    }
    std::printf(
        "%s %s: %d applicable paths, %d proposals (%d across index-matched boundaries), %d with symmetric support, "
        "%d reverse impossible\n",
        c.scene.c_str(), mutationName(c.type), applicable, proposals, crossing, symmetric, impossibleReverse);
    EXPECT_GE(crossing, c.minCrossing) << "too few proposals across index-matched boundaries";
    EXPECT_EQ(unlike, 0) << "edges across index-matched boundaries whose transmittance a connection does not give";
    EXPECT_GE(symmetric, 50) << "too few proposals to mean anything";
    EXPECT_LE(impossibleReverse, symmetric / 10) << "the reverse move should almost always be possible";
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, DetailedBalance,
    ::testing::Values(
        BalanceCase{"cornell-box", MutationType::Bidirectional}, BalanceCase{"cornell-box", MutationType::LensSubpath},
        BalanceCase{"cornell-box", MutationType::Lens}, BalanceCase{"cornell-box", MutationType::Caustic},
        BalanceCase{"veach-mis", MutationType::Bidirectional}, BalanceCase{"veach-mis", MutationType::LensSubpath},
        BalanceCase{"veach-mis", MutationType::Lens}, BalanceCase{"veach-mis", MutationType::Caustic},
        BalanceCase{"veach-bidir", MutationType::Bidirectional}, BalanceCase{"veach-bidir", MutationType::LensSubpath},
        BalanceCase{"veach-bidir", MutationType::Lens}, BalanceCase{"veach-bidir", MutationType::Caustic},
        BalanceCase{"ring-caustic", MutationType::Bidirectional}, BalanceCase{"ring-caustic", MutationType::Lens},
        BalanceCase{"ring-caustic", MutationType::Caustic}, BalanceCase{"pool", MutationType::Lens},
        BalanceCase{"pool", MutationType::MultiChain}, BalanceCase{"cornell-box", MutationType::Manifold},
        BalanceCase{"veach-bidir", MutationType::Manifold}, BalanceCase{"ring-caustic", MutationType::Manifold},
        BalanceCase{"pool", MutationType::Manifold}, BalanceCase{"pool-underwater", MutationType::Manifold},
        BalanceCase{"torus", MutationType::Manifold}, BalanceCase{"glossy-spheres", MutationType::Manifold},
        BalanceCase{"glossy-spheres-analytic", MutationType::Manifold},
        BalanceCase{"cornell-box-thinlens", MutationType::Manifold}, BalanceCase{"veach-mis", MutationType::Manifold},
        BalanceCase{"volumetric-caustic", MutationType::MediumDistance},
        BalanceCase{"volumetric-caustic", MutationType::Manifold}, BalanceCase{"glass-egg", MutationType::Manifold},
        BalanceCase{"glass-egg", MutationType::MediumDistance},
        BalanceCase{"volumetric-caustic-small", MutationType::Manifold, 20, 20 * kGlossyAngle},
        BalanceCase{"volumetric-caustic-small", MutationType::MediumDistance, 20},
        BalanceCase{"portal-toy", MutationType::Portal}, BalanceCase{"portal-box", MutationType::Portal},
        BalanceCase{"cornell-box-portal", MutationType::Portal}),
    [](const ::testing::TestParamInfo<BalanceCase> &info) {
        std::string name = info.param.scene + "_" + mutationName(info.param.type);
        for (char &ch : name)
            if (ch == '-') ch = '_';
        return name;
    });

// Surface coordinates of the new non-specular vertices of y (two per vertex, in a tangent frame of the
// vertex; pinholes and point lights have none).
std::vector<double> surfaceCoordinates(const PathView &y, const std::vector<int> &vertices,
                                       const std::vector<Frame> &frames) {
    std::vector<double> coords;
    for (size_t i = 0; i < vertices.size(); ++i) {
        const Vec3 p = y.vertex(vertices[i]).position();
        coords.push_back(dot(p, frames[i].s));
        coords.push_back(dot(p, frames[i].t));
    }
    return coords;
}

double determinant(std::vector<std::vector<double>> a) {
    const size_t n = a.size();
    double det = 1;
    for (size_t c = 0; c < n; ++c) {
        size_t pivot = c;
        for (size_t r = c + 1; r < n; ++r)
            if (std::abs(a[r][c]) > std::abs(a[pivot][c])) pivot = r;
        if (pivot != c) std::swap(a[pivot], a[c]), det = -det;
        det *= a[c][c];
        if (det == 0) return 0;
        for (size_t r = c + 1; r < n; ++r) {
            const double f = a[r][c] / a[c][c];
            for (size_t k = c; k < n; ++k) a[r][k] -= f * a[c][k];
        }
    }
    return det;
}

// 1 / |det J| for the proposal that `numbers` produce from x, J by central differences; 0 when the
// Jacobian cannot be formed (a difference crosses a discontinuity, a specular vertex, or the number of
// coordinates differs from the number of numbers that move them).
double finiteDifferenceDensity(const Scene &scene, const Mutation &mutation, const MutablePath &x,
                               const std::vector<double> &numbers, const MutablePath &y, const MutationRecord &record) {
    std::vector<int> vertices;
    std::vector<Frame> frames;
    for (int i = record.l + 1; i <= record.l + record.added; ++i) {
        const PathVertex &v = y.vertex(i);
        // The walks weigh the directions they sampled, EVALPDF the directions between vertex positions,
        // which differ by the offset of spawned rays over the edge length (test_path_space.cpp): edges
        // shorter than 1000 offsets are left out, so that this test resolves errors of 1e-3.
        for (const int j : {i - 1, i + 1})
            if (j >= 0 && j < y.length() &&
                (y.vertex(j).position() - v.position()).length() < 1e3 * scene.epsilonAt(v.position()))
                return 0;
        if (v.delta || v.type == VertexType::Medium) return 0;
        if (v.hasDeltaPosition()) continue;
        vertices.push_back(i);
        frames.emplace_back(v.type == VertexType::Surface ? v.its.n : v.ps.n);
    }
    const std::vector<double> base = surfaceCoordinates(y, vertices, frames);
    std::vector<std::vector<double>> columns;
    const double h = 1e-7;
    for (size_t j = 0; j < numbers.size(); ++j) {
        std::vector<double> column;
        bool moved = false, broken = false;
        std::vector<double> plus, minus;
        for (const double sign : {1.0, -1.0}) {
            std::vector<double> u = numbers;
            u[j] += sign * h;
            ReplaySampler sampler(u);
            MutablePath z;
            MutationRecord r;
            if (u[j] <= 0 || u[j] >= 1 || !mutation.sample(scene, sampler, x, z, r) || r.l != record.l ||
                r.m != record.m || r.added != record.added) {
                broken = true;
                break;
            }
            (sign > 0 ? plus : minus) = surfaceCoordinates(z, vertices, frames);
        }
        if (broken) return 0;
        for (size_t r = 0; r < base.size(); ++r) {
            const double forward = (plus[r] - base[r]) / h, backward = (base[r] - minus[r]) / h;
            // One-sided differences that disagree straddle a discontinuity (another surface, an edge).
            if (std::abs(forward - backward) > 1e-3 * (std::abs(forward) + std::abs(backward)) + 1e-9) return 0;
            column.push_back((plus[r] - minus[r]) / (2 * h));
            moved = moved || column.back() != 0;
        }
        if (moved) columns.push_back(column);
    }
    if (columns.size() != base.size()) return 0;
    std::vector<std::vector<double>> jacobian(base.size(), std::vector<double>(base.size()));
    for (size_t r = 0; r < base.size(); ++r)
        for (size_t c = 0; c < base.size(); ++c) jacobian[r][c] = columns[c][r];
    const double det = std::abs(determinant(jacobian));
    return det > 0 ? 1.0 / det : 0.0;
}

// A proposal from x (if the mutation applies) with a nonzero contribution, drawn with `sampler` (whose numbers
// are kept for finite differences).
bool drawProposal(const Scene &scene, const Mutation &mutation, const MutablePath &x, ReplaySampler &sampler,
                  MutablePath &y, MutationRecord &record) {
    return mutation.applies(x) && mutation.sample(scene, sampler, x, y, record) &&
           chainContribution(scene, y).luminance() > 0;
}

struct JacobianCase {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const JacobianCase &c, std::ostream *os) { *os << c.scene << " " << mutationName(c.type); }
    std::string scene;
    MutationType type;
};

class DensityMatchesSampler : public ::testing::TestWithParam<JacobianCase> {};

// Scenes without specular surfaces, where every new vertex is measured by area.
TEST_P(DensityMatchesSampler, FiniteDifferenceJacobian) {
    const JacobianCase &c = GetParam();
    auto scene = testScene(c.scene);
    const MutationSet set = allMutations(*scene);
    const Mutation &mutation = set[static_cast<size_t>(c.type)];
    const std::vector<MutablePath> paths = bdptPaths(*scene, 400, kResolution);
    int checked = 0, lightMoves = 0, apertureMoves = 0;
    double worst = 0;
    for (size_t i = 0; i < paths.size() && checked < 60; ++i) {
        const MutablePath &x = paths[i];
        ReplaySampler sampler({}, 1000 + i);
        MutablePath y;
        MutationRecord record;
        if (!drawProposal(*scene, mutation, x, sampler, y, record)) continue;
        const double fd = finiteDifferenceDensity(*scene, mutation, x, sampler.numbers(), y, record);
        if (!(fd > 0)) continue;
        ++checked;
        double relative;
        if (c.type == MutationType::Bidirectional) {
            // The density of the split that was drawn is one of the terms of T's sum over splits.
            std::vector<double> pFwd, pRev;
            evalDensities(*scene, y, pFwd, pRev);
            relative = kInfinity;
            for (int s = 0; s <= record.added; ++s) {
                if (!isJunction(y, record.l + s)) continue;
                // A new emitter node is chosen with the discrete pmf of emitter selection, which the
                // Jacobian does not see.
                const double pmf = record.l < 0 && s > 0 ? scene->emitterPmf(y.vertex(0).emitter) : 1.0;
                const double term = walkDensity(*scene, y, record.l, s, record.l + record.added + 1, pFwd, pRev);
                relative = std::min(relative, std::abs(term / pmf / fd - 1));
            }
        } else {
            // The manifold perturbation's density includes the discrete choice of its strategy.
            double strategy = 1.0;
            if (c.type == MutationType::Manifold) {
                const auto &manifold = static_cast<const ManifoldPerturbation &>(mutation);
                const int fixed = record.source == record.l ? record.m : record.l;
                strategy = manifold.classificationProbability(x, {record.source, record.moving, fixed}) /
                           static_cast<double>(manifold.sources(x).size());
                // The endpoint position perturbation: the source is a supernode and x_b the light's or the
                // aperture's node.
                lightMoves += record.source < 0;
                apertureMoves += record.source >= x.length();
            }
            relative = std::abs(mutation.density(*scene, x, y, record) / strategy / fd - 1);
        }
        worst = std::max(worst, relative);
        EXPECT_LT(relative, 2e-3) << "path " << i << ": density disagrees with the sampler's Jacobian";
    }
    std::printf("%s %s: %d Jacobians (%d light and %d aperture position moves), worst relative difference %.2g\n",
                c.scene.c_str(), mutationName(c.type), checked, lightMoves, apertureMoves, worst);
    EXPECT_GE(checked, 20) << "too few proposals checked";
    // cornell-box's light is planar (veach-mis's are spheres, whose position moves always fail); the thin
    // lens variant adds aperture moves.
    if (c.type == MutationType::Manifold && c.scene.rfind("cornell-box", 0) == 0) {
        EXPECT_GE(lightMoves, 3) << "too few light position moves checked";
    }
    if (c.type == MutationType::Manifold && c.scene == "cornell-box-thinlens") {
        EXPECT_GE(apertureMoves, 3) << "too few aperture position moves checked";
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, DensityMatchesSampler,
                         ::testing::Values(JacobianCase{"cornell-box", MutationType::Bidirectional},
                                           JacobianCase{"cornell-box", MutationType::LensSubpath},
                                           JacobianCase{"cornell-box", MutationType::Lens},
                                           JacobianCase{"cornell-box", MutationType::Caustic},
                                           JacobianCase{"veach-mis", MutationType::Bidirectional},
                                           JacobianCase{"veach-mis", MutationType::Lens},
                                           JacobianCase{"veach-mis", MutationType::Caustic},
                                           JacobianCase{"cornell-box", MutationType::Manifold},
                                           JacobianCase{"cornell-box-thinlens", MutationType::Manifold},
                                           JacobianCase{"veach-mis", MutationType::Manifold}),
                         [](const ::testing::TestParamInfo<JacobianCase> &info) {
                             std::string name = info.param.scene + "_" + mutationName(info.param.type);
                             for (char &ch : name)
                                 if (ch == '-') ch = '_';
                             return name;
                         });

// The medium-distance perturbation (path/medium_distance_perturbation.h) through volumetric-caustic's fog: its
// proposal keeps the direction from the anchor, so its sampler is one-dimensional in the distance t'. T(x -> y)
// times t'^2 (the volume element along the fixed direction) and the number of sources must be the density of t'
// under the random numbers, 1/2 (the sign) over |dt'/du| by central differences. The t'^2 itself is checked by
// rendering (test_erpt: bursts of this perturbation alone agree with BDPT).
TEST(MediumDistance, DensityMatchesSampler) {
    auto scene = testScene("volumetric-caustic");
    const MediumDistancePerturbation mutation;
    int checked = 0;
    double worst = 0;
    const std::vector<MutablePath> paths = bdptPaths(*scene, 600, kResolution);
    for (size_t i = 0; i < paths.size() && checked < 60; ++i) {
        const MutablePath &x = paths[i];
        MutablePath y;
        MutationRecord record;
        ReplaySampler sampler({}, 2000 + i);
        if (!drawProposal(*scene, mutation, x, sampler, y, record)) continue;
        const Vec3 &anchor = x.vertex(record.source).position();
        const auto distance = [&](double delta) {
            std::vector<double> u = sampler.numbers();
            u[1] += delta;
            ReplaySampler replay(u);
            MutablePath z;
            MutationRecord r;
            return mutation.sample(*scene, replay, x, z, r) ? (z.vertex(record.moving).position() - anchor).length()
                                                            : -1.0;
        };
        constexpr double h = 1e-7;
        const double plus = distance(h), minus = distance(-h);
        if (sampler.numbers()[1] <= h || sampler.numbers()[1] >= 1 - h || plus < 0 || minus < 0) continue;
        const double t = (y.vertex(record.moving).position() - anchor).length();
        const double sampled = 0.5 / std::abs((plus - minus) / (2 * h));
        const double reported =
            mutation.density(*scene, x, y, record) * t * t * static_cast<double>(mutation.sources(x).size());
        ++checked;
        worst = std::max(worst, std::abs(reported / sampled - 1));
        EXPECT_NEAR(reported / sampled, 1.0, 1e-5) << "path " << i;
    }
    std::printf("volumetric-caustic mediumDistance: %d densities, worst relative difference %.2g\n", checked, worst);
    EXPECT_GE(checked, 20) << "too few proposals checked";
}

// The manifold perturbation across specular and glossy chains. Only x'_b moves freely (the chain vertices follow
// it, on x's offset manifold), so the area density of x'_b under the random numbers of the direction kernel,
// 1 / |det J| by central differences, is T_M(x -> y) of manifold_perturbation.h: the reported canonical density
// times measureConversion() (rho of each ideal specular sub-chain, and the offset Jacobian), over the strategy's
// probability.
//
// Through media the sampler also has to cross the traced edges (free-flight survival, the walk's own edge
// densities), which the Jacobian does not see; T holds them, and rho the sensor walk's densities of the ideal
// sub-chains' edges (manifold_perturbation.h), so both come out of the comparison: walkedOverSensor(). In
// glass-egg (a g = 0.8 medium in glass) medium vertices join the chains (§6.7), more often with a larger
// classification angle dtheta (20 degrees in glass-egg-largelight). A medium x'_b has three coordinates, its
// position, against the vMF's two numbers and its free-flight number (the first chain samples its distance); the
// walk of the second chain places it (glass-egg at the default dtheta: most proposals into the medium move one).
class ManifoldChains : public ::testing::TestWithParam<std::string> {};

// The walk's probability of crossing the edges it traced from `from` to `to` (those into a medium vertex of a
// chain are placed, not traced), over the sensor walk's densities of the edges of ideal sub-chains. An edge into a
// medium x_b is left out too: the first chain samples its length, which the sampler's Jacobian sees (its third
// column), and the second chain places it.
double walkedOverSensor(const PathView &y, int from, int to) {
    const int dir = to > from ? 1 : -1;
    const int mode = modeIndex(dir > 0 ? TransportMode::Importance : TransportMode::Radiance);
    double ratio = 1.0;
    for (int u = from; u != to;) {
        int w = u + dir;
        while (w != to && !isNonSpecular(y.vertex(w))) w += dir;
        for (int e = u; e != w; e += dir) {
            const PathEdge &edge = y.edge(std::min(e, e + dir));
            const bool held = e + dir == w && y.vertex(w).type == VertexType::Medium;
            ratio *= (held ? 1.0 : edge.pdf[mode]) /
                     (std::abs(w - u) > 1 ? edge.pdf[modeIndex(TransportMode::Radiance)] : 1.0);
        }
        u = w;
    }
    return ratio;
}

TEST_P(ManifoldChains, MovedVertexDensityMatchesSampler) {
    auto scene = testScene(GetParam());
    // glass-egg-largelight: medium vertices join chains often at dtheta = 20 degrees; glass-egg: at the default
    // dtheta they rarely do, and most proposals that reach the medium move a medium x_b.
    const bool chainsInMedia = GetParam() == "glass-egg-largelight", mediumEnds = GetParam() == "glass-egg";
    const ManifoldPerturbation mutation(*scene, 50.0, chainsInMedia ? 20 * kGlossyAngle : kGlossyAngle);
    const std::vector<MutablePath> paths = bdptPaths(*scene, 1500, kResolution);
    int checked = 0, firstChain = 0, secondChain = 0, glossy = 0, mediumChains = 0, mediumMoves = 0, outliers = 0;
    double worst = 0;
    // 80 proposals, then (glass-egg) more until 20 of them moved a medium x_b.
    for (size_t i = 0; i < paths.size() && (checked < 80 || (mediumEnds && mediumMoves < 20)); ++i) {
        const MutablePath &x = paths[i];
        if (!mutation.applies(x)) continue;
        for (uint64_t j = 0; j < 4; ++j) {
            ReplaySampler sampler({}, 7000 + 4 * i + j);
            MutablePath y;
            MutationRecord record;
            if (!mutation.sample(*scene, sampler, x, y, record) || !(chainContribution(*scene, y).luminance() > 0))
                continue;
            const int source = record.source, fixed = source == record.l ? record.m : record.l, moving = record.moving;
            ASSERT_TRUE((moving - source) * (fixed - moving) > 0) << "x_b must lie between x_a and x_c";
            const bool specular1 = std::abs(moving - source) > 1, specular2 = std::abs(fixed - moving) > 1;
            if (!specular1 && !specular2) continue;
            // x'_b's coordinates in a frame of its surface, against the two numbers of the vMF sample; a medium
            // x'_b's position in space, against those and the number its free-flight distance was sampled with
            // (the one after them that moves it).
            const bool inMedium = y.vertex(moving).type == VertexType::Medium;
            if (checked >= 80 && !inMedium) continue;
            const Frame frame(inMedium ? Vec3(0, 0, 1) : y.vertex(moving).its.n);
            const auto coords = [&](const PathView &z) {
                const Vec3 p = z.vertex(moving).position();
                return Vec3(dot(p, frame.s), dot(p, frame.t), inMedium ? dot(p, frame.n) : 0.0);
            };
            const double h = 1e-7;
            const auto column = [&](size_t index, Vec3 &out) {
                Vec3 sides[2];
                for (int side = 0; side < 2; ++side) {
                    std::vector<double> u = sampler.numbers();
                    if (index >= u.size()) return false;
                    u[index] += side == 0 ? h : -h;
                    ReplaySampler replay(u);
                    MutablePath z;
                    MutationRecord r;
                    if (!(u[index] > 0 && u[index] < 1 && mutation.sample(*scene, replay, x, z, r) &&
                          r.source == source && r.l == record.l && r.m == record.m && r.moving == moving))
                        return false;
                    sides[side] = coords(z);
                }
                const Vec3 base = coords(y), fwd = (sides[0] - base) * (1 / h), bwd = (base - sides[1]) * (1 / h);
                for (int c = 0; c < 3; ++c)
                    if (std::abs(fwd[c] - bwd[c]) > 1e-4 * (std::abs(fwd[c]) + std::abs(bwd[c])) + 1e-9) return false;
                out = (sides[0] - sides[1]) * (1 / (2 * h));
                return true;
            };
            Vec3 columns[3] = {Vec3(0.0), Vec3(0.0), Vec3(0, 0, 1)};
            bool ok = column(1, columns[0]) && column(2, columns[1]);
            if (ok && inMedium) {
                ok = false;
                for (size_t index = 3; index < sampler.numbers().size() && !ok; ++index)
                    ok = column(index, columns[2]) && columns[2].length() > 0;
            }
            // The homogeneous medium spreads one number over its three channels' exponentials (medium/
            // homogeneous.cpp): each third of it covers every distance, so in a grey medium (glass-egg's) the
            // Jacobian of one third is 3 times the inverse of the distance's density.
            const double det = std::abs(dot(columns[0], cross(columns[1], columns[2]))) / (inMedium ? 3 : 1);
            if (!ok || !(det > 0)) continue;
            const ManifoldPerturbation::Strategy st{source, moving, fixed};
            const double strategy =
                mutation.classificationProbability(x, st) / static_cast<double>(mutation.sources(x).size());
            double crossed = walkedOverSensor(y, source, moving);
            if (specular2) crossed *= walkedOverSensor(y, fixed, moving);
            const double manifold =
                mutation.density(*scene, x, y, record) / strategy * mutation.measureConversion(y, st) / crossed;
            const double relative = std::abs(manifold * det - 1);
            worst = std::max(worst, relative);
            ++checked;
            firstChain += specular1;
            mediumMoves += inMedium;
            secondChain += specular2;
            for (int v = std::min(source, fixed) + 1; v < std::max(source, fixed); ++v)
                if (v != moving && isNonSpecular(y.vertex(v))) {
                    ++(y.vertex(v).type == VertexType::Medium ? mediumChains : glossy);
                    break;
                }
            // Rays leave surfaces from offset origins (Scene::spawnRay), which the sampler sees and the
            // densities, built from vertex positions, do not; and traced chains may land up to 100 ray offsets
            // from the walked ones (manifold_perturbation.cpp, kRayOffsets). Near a focus of a curved mirror
            // this shows as errors of a few 1e-3, at worst 1.5e-2 (ring-caustic) and 2.02e-2 (torus, one of 80
            // proposals, after a change of the emitters' position sampling drew other paths), in a few proposals.
            // A wrong factor (a missing index ratio, a cosine of the old direction) is off in every proposal of its
            // kind, by far more: the count of outliers below is the real test, the cap only a guard against a
            // gross error in one proposal.
            outliers += relative > 2e-3;
            EXPECT_LT(relative, 5e-2) << "path " << i << " proposal " << j << " (source " << source << ", moving "
                                      << moving << ", fixed " << fixed << ")";
        }
    }
    std::printf(
        "%s manifold: %d proposals across chains (%d first, %d second, %d with glossy and %d with medium vertices "
        "walked as specular, %d moving a medium x_b), worst %.2g, %d above 2e-3\n",
        GetParam().c_str(), checked, firstChain, secondChain, glossy, mediumChains, mediumMoves, worst, outliers);
    EXPECT_GE(checked, 20) << "too few proposals checked";
    EXPECT_LE(outliers, checked / 20) << "more than 5% of the proposals are off by more than 2e-3";
    if (GetParam().rfind("glossy-spheres", 0) == 0) {
        EXPECT_GE(glossy, 20) << "too few glossy chains checked";
    }
    if (chainsInMedia) {
        EXPECT_GE(mediumChains, 20) << "too few medium chains checked";
    }
    if (mediumEnds) {
        EXPECT_GE(mediumMoves, 20) << "too few medium x_b checked";
    }
}

INSTANTIATE_TEST_SUITE_P(Scenes, ManifoldChains,
                         ::testing::Values("ring-caustic", "pool", "pool-underwater", "torus", "glossy-spheres",
                                           "glossy-spheres-analytic", "glass-egg-largelight", "glass-egg"),
                         [](const ::testing::TestParamInfo<std::string> &info) {
                             std::string name = info.param;
                             for (char &ch : name)
                                 if (ch == '-') ch = '_';
                             return name;
                         });

// The offsets o = T^T h of y's glossy chain vertices (in chain order from x_a), or nullopt when one cannot be
// formed; `moved` replaces vertex `at`'s intersection.
std::optional<std::vector<Vec2>> glossyOffsets(const PathView &y, const std::vector<int> &glossy, int at,
                                               const Intersection &moved) {
    std::vector<Vec2> offsets;
    const auto position = [&](int v) { return v == at ? moved.p : y.vertex(v).position(); };
    for (const int v : glossy) {
        const auto mv =
            ManifoldVertex::constrained(v == at ? moved : y.vertex(v).its, position(v - 1), position(v + 1), false);
        if (!mv) return std::nullopt;
        offsets.push_back(mv->offset);
    }
    return offsets;
}

// The offset Jacobian |∂x / ∂o| (manifold/offset_jacobian.h) of proposals through glossy chains without ideal
// specular vertices (there measureConversion() is that factor alone) equals 1 / |det ∂o / ∂x| with x_a, x_b
// and x_c held, by central differences: each glossy vertex moves along a tangent of its surface and is put
// back on it by a ray along the normal, and the offsets of all glossy vertices are recomputed from positions.
class GlossyOffsetJacobian : public ::testing::TestWithParam<std::string> {};

TEST_P(GlossyOffsetJacobian, MatchesFiniteDifferences) {
    auto scene = testScene(GetParam());
    const ManifoldPerturbation mutation(*scene, 50.0, kGlossyAngle);
    const std::vector<MutablePath> paths = bdptPaths(*scene, 1500, kResolution);
    int checked = 0, multiple = 0;
    double worst = 0;
    for (size_t i = 0; i < paths.size() && checked < 60; ++i) {
        const MutablePath &x = paths[i];
        if (!mutation.applies(x)) continue;
        IndependentSampler sampler(31, i, 0);
        MutablePath y;
        MutationRecord record;
        if (!mutation.sample(*scene, sampler, x, y, record) || !(chainContribution(*scene, y).luminance() > 0))
            continue;
        const int source = record.source, fixed = source == record.l ? record.m : record.l;
        std::vector<int> glossy;
        for (int v = std::min(source, fixed) + 1; v < std::max(source, fixed); ++v)
            if (v != record.moving) glossy.push_back(v);
        if (glossy.empty()) continue;
        const size_t n = 2 * glossy.size();
        std::vector<std::vector<double>> jacobian(n, std::vector<double>(n));
        bool ok = true;
        const double h = 1e-6;
        for (size_t g = 0; g < glossy.size() && ok; ++g) {
            const PathVertex &v = y.vertex(glossy[g]);
            const Frame frame(v.its.n);
            for (int axis = 0; axis < 2 && ok; ++axis) {
                std::vector<Vec2> sides[2];
                for (int side = 0; side < 2 && ok; ++side) {
                    const Vec3 step = (axis == 0 ? frame.s : frame.t) * (side == 0 ? h : -h);
                    Intersection moved;
                    ok = scene->intersect(Ray(v.position() + step + v.its.n * 1e-3, -v.its.n), moved) &&
                         moved.shape == v.its.shape;
                    const auto offsets = ok ? glossyOffsets(y, glossy, glossy[g], moved) : std::nullopt;
                    ok = ok && offsets.has_value();
                    if (ok) sides[side] = *offsets;
                }
                for (size_t r = 0; r < glossy.size() && ok; ++r) {
                    const Vec2 d = (sides[0][r] - sides[1][r]) * (1 / (2 * h));
                    jacobian[2 * r][2 * g + axis] = d.x;
                    jacobian[2 * r + 1][2 * g + axis] = d.y;
                }
            }
        }
        const double det = ok ? std::abs(determinant(jacobian)) : 0.0;
        if (!(det > 0)) continue;
        const double j = mutation.measureConversion(y, {source, record.moving, fixed});
        const double relative = std::abs(j * det - 1);
        worst = std::max(worst, relative);
        ++checked;
        multiple += glossy.size() > 1;
        EXPECT_LT(relative, 1e-4) << "path " << i << ": offset Jacobian " << j << ", finite differences " << 1 / det;
    }
    std::printf("%s offset Jacobian: %d proposals (%d with several glossy vertices), worst %.2g\n", GetParam().c_str(),
                checked, multiple, worst);
    EXPECT_GE(checked, 20) << "too few glossy chains checked";
}

// Meshes, whose charts are exact per triangle, and analytic spheres, whose glossy frame turns with the normal
// (specular_constraint.h).
INSTANTIATE_TEST_SUITE_P(Scenes, GlossyOffsetJacobian, ::testing::Values("glossy-spheres", "glossy-spheres-analytic"),
                         [](const ::testing::TestParamInfo<std::string> &info) { return gtestName(info.param); });

// Detailed balance in its integral form on glossy-spheres, which sees the offset Jacobian and the classification
// probabilities through the sampler itself. For states x ~ pi and proposals y ~ T(x -> .), accepted with
// a(x -> y), the flux pi(x) T(x -> y) a(x -> y) is symmetric under x <-> y exactly when the reported T is the
// sampler's density up to the state-independent constant (the selection of the mutation); then every
// antisymmetric g(x, y) has
//     E[a(x -> y) g(x, y)] = 0.
// Two of them: g = log(J(y) / J(x)), J the offset Jacobian of the move's strategy (manifold/offset_jacobian.h),
// and g = log(P(st | y) / P(st | x)), the strategy's probability, which the gold sphere's checkerboard roughness
// makes vary. A density with a wrong power of J, J at the wrong end of the move, or the classification
// probabilities left to cancel, biases the acceptance towards one side. x ~ pi comes from BDPT: each path
// weighted by its strategy's luminance contribution (MIS weight f / p), raster positions uniform over the film.
TEST(GlossyFlux, BalancedAcrossOffsetJacobianAndClassification) {
    constexpr uint64_t kFluxSamples = 100000;
    auto scene = testScene("glossy-spheres");
    const ManifoldPerturbation mutation(*scene, 50.0, kGlossyAngle);
    Properties props(ObjectKind::Integrator, "bdpt", {});
    props.set("maxDepth", Properties::Type::Integer, int64_t(maxVertices(*scene) - 1), {});
    props.set("rrDepth", Properties::Type::Integer, int64_t(100), {});
    const BDPT bdpt(props);
    const auto strategyProbability = [&](const PathView &z, const ManifoldPerturbation::Strategy &st) {
        return mutation.classificationProbability(z, st) / static_cast<double>(mutation.sources(z).size());
    };
    // Per raster sample and statistic: the weighted sum of a g over its paths' proposals.
    std::vector<double> flux[2];
    int moves[2] = {0, 0};
    for (uint64_t sample = 0; sample < kFluxSamples; ++sample) {
        IndependentSampler sampler(23, sample, 0);
        const Vec2 raster(sampler.next1D() * kResolution, sampler.next1D() * kResolution);
        double sum[2] = {0, 0};
        bdpt.evaluate(*scene, sampler, raster, [&](const StrategySample &s) {
            const double w = s.value.luminance();
            if (!(w > 0)) return;
            const MutablePath x(*s.path);
            const double piX = chainContribution(*scene, x).luminance();
            if (!(piX > 0) || !mutation.applies(x)) return;
            for (uint64_t j = 0; j < 4; ++j) {
                IndependentSampler proposal(29, sample * 64 + static_cast<uint64_t>(s.s * 8 + s.t), j);
                MutablePath y;
                MutationRecord record;
                if (!mutation.sample(*scene, proposal, x, y, record)) continue;
                const double piY = chainContribution(*scene, y).luminance();
                if (!(piY > 0)) continue;
                const ManifoldPerturbation::Strategy st{record.source, record.moving,
                                                        record.source == record.l ? record.m : record.l};
                const double g[2] = {
                    std::log(ManifoldPerturbation::offsetFactor(y, st) / ManifoldPerturbation::offsetFactor(x, st)),
                    std::log(strategyProbability(y, st) / strategyProbability(x, st))};
                if (g[0] == 0 && g[1] == 0) continue;
                Proposal p;
                p.target = piY;
                p.forward = mutation.density(*scene, x, y, record);
                p.backward = mutation.density(*scene, y, x, record.reverse());
                const double a = acceptance(piX, p);
                for (int k = 0; k < 2; ++k)
                    if (g[k] != 0) {
                        ++moves[k];
                        sum[k] += w * a * g[k] / 4;
                    }
            }
        });
        for (int k = 0; k < 2; ++k) flux[k].push_back(sum[k]);
    }
    const char *names[2] = {"log(J(y) / J(x))", "log(P(st | y) / P(st | x))"};
    for (int k = 0; k < 2; ++k) {
        const double n = static_cast<double>(flux[k].size());
        double mean = 0, variance = 0;
        for (const double f : flux[k]) mean += f / n;
        for (const double f : flux[k]) variance += (f - mean) * (f - mean) / (n - 1);
        const double error = std::sqrt(variance / n);
        std::printf("glossy-spheres flux: %d moves that change %s, E[a g] = %.3g +- %.2g\n", moves[k], names[k], mean,
                    error);
        EXPECT_GE(moves[k], 500) << "too few moves change " << names[k];
        EXPECT_LT(std::abs(mean), 4 * error) << "the acceptance favours one direction of " << names[k];
    }
}

}  // namespace
}  // namespace pf::test
