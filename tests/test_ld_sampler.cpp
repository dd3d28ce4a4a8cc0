// The low-discrepancy pixel sampler (core/ld_sampler.h): its stratification (every power-of-two run of a
// pixel's samples is a (0,m,2)-net in each 2D request and stratified in each 1D request), the uniformity of
// each single number across pixels (chi-square; what keeps estimators unbiased), the independence of
// different requests, the independent numbers past Mitsuba's `dimension`, and what it is for: a lower error
// of the path tracer at the same sample count on the Cornell box, whose file asks for `sobol`.
#include <gtest/gtest.h>

#include "core/ld_sampler.h"
#include "core/owen_sobol.h"
#include "image/metrics.h"
#include "support/chi2.h"
#include "support/nets.h"
#include "test_mlt_common.h"

namespace pf::test {
namespace {

// Samples [first, first + count) of one pixel: request `request` of the 2D (or 1D) requests.
std::vector<Vec2> points2D(LowDiscrepancySampler &s, uint64_t seed, uint64_t pixel, uint64_t first, uint64_t count,
                           int request) {
    std::vector<Vec2> out;
    for (uint64_t i = first; i < first + count; ++i) {
        s.start(seed, pixel, i);
        Vec2 p;
        for (int r = 0; r <= request; ++r) p = s.next2D();
        out.push_back(p);
    }
    return out;
}
std::vector<double> points1D(LowDiscrepancySampler &s, uint64_t seed, uint64_t pixel, uint64_t first, uint64_t count,
                             int request) {
    std::vector<double> out;
    for (uint64_t i = first; i < first + count; ++i) {
        s.start(seed, pixel, i);
        double u = 0;
        for (int r = 0; r <= request; ++r) u = s.next1D();
        out.push_back(u);
    }
    return out;
}

TEST(OwenSobol, SecondDimensionMatchesItsDirectionNumbers) {
    // The table lookup against the direct product with the direction numbers, bit by bit.
    for (uint32_t index : {0u, 1u, 2u, 3u, 255u, 256u, 0x12345u, 0xdeadbeefu, 0xffffffffu}) {
        uint32_t v = 1u << 31, expected = 0;
        for (uint32_t i = index; i; i >>= 1, v ^= v >> 1)
            if (i & 1u) expected ^= v;
        EXPECT_EQ(sobol::secondDimension(index), expected) << index;
    }
    // The first points of the (0,2)-sequence: (0,0), (1/2,1/2), (1/4,3/4), (3/4,1/4).
    EXPECT_EQ(sobol::secondDimension(2), 3u << 30);
    EXPECT_EQ(sobol::firstDimension(2), 1u << 30);
}

// The shortcuts the sampler takes equal the definitions: the shuffled index from the reversed index, the second
// coordinate's reversal from its table, and both halves of a word reversed at once.
TEST(OwenSobol, ShuffledPointsFromTheReversedIndex) {
    PCG32 rng(5, 7);
    for (int k = 0; k < 10000; ++k) {
        const uint32_t index = rng.nextUInt(), seed = rng.nextUInt(), other = rng.nextUInt();
        const uint32_t shuffled = sobol::nestedUniformScramble(index, seed);
        ASSERT_EQ(sobol::shuffledIndex(sobol::reverseBits(index), seed), shuffled);
        ASSERT_EQ(sobol::reversedSecondDimension(shuffled), sobol::reverseBits(sobol::secondDimension(shuffled)));
        const uint64_t both = sobol::reverseBits64((static_cast<uint64_t>(other) << 32) | index);
        ASSERT_EQ(both >> 32, sobol::reverseBits(index));
        ASSERT_EQ(static_cast<uint32_t>(both), sobol::reverseBits(other));
    }
}

TEST(OwenSobol, ScrambleIsAPermutationThatKeepsPrefixes) {
    // An Owen scramble maps binary intervals to binary intervals: the top k bits of the result depend only on
    // the top k bits of the input. Over all 2^16 values of the top 16 bits it is a bijection.
    for (uint32_t seed : {0u, 1u, 0x9e3779b9u}) {
        std::set<uint32_t> images;
        for (uint32_t hi = 0; hi < (1u << 16); ++hi) {
            const uint32_t a = sobol::nestedUniformScramble(hi << 16, seed);
            const uint32_t b = sobol::nestedUniformScramble((hi << 16) | 0xffffu, seed);
            EXPECT_EQ(a >> 16, b >> 16);
            images.insert(a >> 16);
        }
        EXPECT_EQ(images.size(), size_t{1} << 16);
    }
}

TEST(LowDiscrepancySampler, EveryPowerOfTwoRunOfAPixelIsANet) {
    LowDiscrepancySampler s;
    for (uint64_t pixel : {0u, 1u, 977u})
        for (int request = 0; request < 6; ++request)
            for (int m = 0; m <= 10; ++m) {
                const uint64_t n = uint64_t{1} << m;
                // The first 2^m samples, and the next 2^m (a time-budgeted render that ran 2^(m+1) passes).
                for (uint64_t first : {uint64_t{0}, n}) {
                    EXPECT_TRUE(isNet(points2D(s, 5, pixel, first, n, request), m))
                        << "pixel " << pixel << " 2D request " << request << " samples " << first << "+" << n;
                    EXPECT_TRUE(isStratified(points1D(s, 5, pixel, first, n, request)))
                        << "pixel " << pixel << " 1D request " << request << " samples " << first << "+" << n;
                }
            }
}

// Owen scrambling makes every single point uniform: the i-th sample over many pixels (or seeds) is a sample of
// the uniform distribution, for every i; two different requests of one sample are independent.
TEST(LowDiscrepancySampler, EachNumberIsUniformAndRequestsAreIndependent) {
    constexpr int kBins = 32, kPixels = 400000, kTests = 4 * 4;
    LowDiscrepancySampler s;
    const std::vector<double> expected(kBins * kBins, static_cast<double>(kPixels) / (kBins * kBins));
    for (uint64_t index : {0u, 1u, 6u, 1000u}) {
        std::vector<double> first2D(kBins * kBins), pairs2D(kBins * kBins), pairs1D(kBins * kBins),
            mixed(kBins * kBins);
        const auto bin = [](double u) { return std::min(kBins - 1, static_cast<int>(u * kBins)); };
        for (int pixel = 0; pixel < kPixels; ++pixel) {
            s.start(11, pixel, index);
            const Vec2 a = s.next2D(), b = s.next2D();
            const double u = s.next1D(), v = s.next1D();
            first2D[bin(a.x) * kBins + bin(a.y)] += 1;
            pairs2D[bin(a.x) * kBins + bin(b.y)] += 1;
            pairs1D[bin(u) * kBins + bin(v)] += 1;
            mixed[bin(a.y) * kBins + bin(u)] += 1;
        }
        for (const auto &[name, histogram] : {std::pair{"2D request 0", &first2D},
                                              {"2D requests 0 and 1", &pairs2D},
                                              {"1D requests 0 and 1", &pairs1D},
                                              {"2D request 0 and 1D 0", &mixed}}) {
            const Chi2Result r = chi2Histogram(*histogram, expected, 0.01, kTests);
            EXPECT_TRUE(r.passed) << name << ", sample " << index << ": " << r.report;
        }
    }
}

TEST(LowDiscrepancySampler, SameSampleSameNumbersAndPastTheDimensionIndependentOnes) {
    LowDiscrepancySampler a(2), b(2);
    a.start(3, 40, 17);
    b.start(3, 40, 17);
    for (int k = 0; k < 8; ++k) {
        EXPECT_EQ(a.next1D(), b.next1D());
        const Vec2 p = a.next2D(), q = b.next2D();
        EXPECT_EQ(p.x, q.x);
        EXPECT_EQ(p.y, q.y);
    }
    // Past two 1D and two 2D requests the numbers are the independent sampler's of the same sample.
    IndependentSampler independent(3, 40, 17);
    a.start(3, 40, 17);
    a.next1D(), a.next1D(), a.next2D(), a.next2D();
    EXPECT_EQ(a.next1D(), independent.next1D());
    const Vec2 p = a.next2D(), q = independent.next2D();
    EXPECT_EQ(p.x, q.x);
    EXPECT_EQ(p.y, q.y);
    // Another pixel or seed gives other numbers.
    a.start(3, 41, 17);
    b.start(4, 40, 17);
    LowDiscrepancySampler c;
    c.start(3, 40, 17);
    const double u = c.next1D();
    EXPECT_NE(a.next1D(), u);
    EXPECT_NE(b.next1D(), u);
}

// A stratified request's numbers depend on (seed, pixel, sample, kind, request) alone: not on how 1D and 2D
// requests interleave, nor on what the sampler drew before it was restarted. The sampler computes each kind's
// next request ahead of time, and this is what that must keep: one sampler is restarted on samples of two
// pixels, each consumed partly in a random interleaving, and every number is checked against a fresh sampler
// that asks for the same request in a fixed order, and against a `sobol` sampler (every request stratified),
// whose stratified requests are the same numbers: a request's seeds do not depend on the dimension. Covers
// `sobol` and a `dimension` of 3, where the computing ahead stops at the last stratified request. (Requests
// past the dimension share one independent stream in the order they are made, so their numbers do depend on
// the interleaving.)
TEST(LowDiscrepancySampler, StratifiedNumbersDependOnlyOnTheirRequest) {
    for (const int dimension : {0, 3}) {
        const size_t checked = dimension == 0 ? SIZE_MAX : static_cast<size_t>(dimension);
        LowDiscrepancySampler reused(dimension);
        PCG32 rng(11, 3);
        for (int round = 0; round < 200; ++round) {
            const uint64_t pixel = 5 + rng.nextUInt(2), sample = rng.nextUInt(40);
            reused.start(9, pixel, sample);
            std::vector<double> got1D;
            std::vector<Vec2> got2D;
            for (int k = static_cast<int>(rng.nextUInt(12)); k > 0; --k) {
                if (rng.nextUInt(2))
                    got1D.push_back(reused.next1D());
                else
                    got2D.push_back(reused.next2D());
            }
            LowDiscrepancySampler fresh(dimension), sobol;
            fresh.start(9, pixel, sample);
            sobol.start(9, pixel, sample);
            for (size_t r = 0; r < std::min(got1D.size(), checked); ++r) {
                ASSERT_EQ(fresh.next1D(), got1D[r]) << dimension << " 1D " << r;
                ASSERT_EQ(sobol.next1D(), got1D[r]) << dimension << " 1D " << r;
            }
            fresh.start(9, pixel, sample);
            sobol.start(9, pixel, sample);
            for (size_t r = 0; r < std::min(got2D.size(), checked); ++r) {
                const Vec2 p = fresh.next2D(), q = sobol.next2D();
                ASSERT_EQ(p.x, got2D[r].x) << dimension << " 2D " << r;
                ASSERT_EQ(p.y, got2D[r].y) << dimension << " 2D " << r;
                ASSERT_EQ(q.x, got2D[r].x) << dimension << " 2D " << r;
                ASSERT_EQ(q.y, got2D[r].y) << dimension << " 2D " << r;
            }
        }
    }
}

// Sampler::startPart: part 1 begins at request kRequestsPerPart of each kind whatever part 0 consumed (below that),
// so over a pixel's first 2^m samples, each of which made a random number of requests before it, the first 2D
// and 1D requests of part 1 are a (0,m,2)-net and stratified, as a fresh sampler's requests at that index are.
// Without startPart they would be the random requests' successors: not a net. Where part 0 reaches past the
// part's start, the part begins right after it (no request is made twice in a sample).
TEST(LowDiscrepancySampler, PartsStartAtFixedRequests) {
    constexpr int kM = 6;
    LowDiscrepancySampler s, fresh;
    PCG32 rng(3, 9);
    std::vector<Vec2> part1, without;
    std::vector<double> part1D;
    for (uint64_t i = 0; i < (uint64_t{1} << kM); ++i) {
        const int before = static_cast<int>(rng.nextUInt(20));
        for (const bool jump : {true, false}) {
            s.start(4, 21, i);
            for (int k = 0; k < before; ++k) s.next2D(), s.next1D();
            if (jump) s.startPart(1);
            (jump ? part1 : without).push_back(s.next2D());
            if (jump) part1D.push_back(s.next1D());
        }
        fresh.start(4, 21, i);
        fresh.startPart(1);
        const Vec2 p = fresh.next2D();
        ASSERT_EQ(p.x, part1.back().x);
        ASSERT_EQ(p.y, part1.back().y);
    }
    EXPECT_TRUE(isNet(part1, kM));
    EXPECT_TRUE(isStratified(part1D));
    EXPECT_FALSE(isNet(without, kM));
    // Part 0 past part 1's start: part 1 continues after it.
    s.start(4, 21, 0);
    fresh.start(4, 21, 0);
    for (uint32_t k = 0; k < LowDiscrepancySampler::kRequestsPerPart + 5; ++k) s.next2D(), fresh.next2D();
    s.startPart(1);
    const Vec2 a = s.next2D(), b = fresh.next2D();
    EXPECT_EQ(a.x, b.x);
    EXPECT_EQ(a.y, b.y);
}

// What the sampler is for. The path tracer on the Cornell box (its file asks for `sobol`) at 16 samples per
// pixel, against its copy with `independent`, each over eight seeds, both against one reference: the
// stratified pixel positions, light samples and first bounces lower the mean squared error clearly (the
// figure is printed); a sampler whose numbers were merely uniform, unstratified, would come out level.
TEST(LowDiscrepancySampler, LowersThePathTracersErrorOnTheCornellBox) {
    constexpr int kRes = 24, kSpp = 16, kSeeds = 8;
    const auto ld = loadMLTTestScene("cornell-box", kRes, kSpp);
    const auto independent = loadMLTTestScene("cornell-box-independent", kRes, kSpp);
    ASSERT_TRUE(ld->sensor().sampleSequence().lowDiscrepancy);
    ASSERT_FALSE(independent->sensor().sampleSequence().lowDiscrepancy);
    const auto render = [](const Scene &scene, int64_t spp, uint64_t seed) {
        return renderTestImage(scene, "path", spp, seed);
    };
    const Bitmap reference = render(*ld, 2048, 99);
    double mseLD = 0, mseIndependent = 0;
    for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
        mseLD += computeMetrics(render(*ld, kSpp, seed), reference).mse / kSeeds;
        mseIndependent += computeMetrics(render(*independent, kSpp, seed), reference).mse / kSeeds;
    }
    std::printf("cornell-box %d², path at %d spp over %d seeds: MSE %.4g (sobol) against %.4g (independent), %.2fx\n",
                kRes, kSpp, kSeeds, mseLD, mseIndependent, mseIndependent / mseLD);
    EXPECT_LT(mseLD, 0.7 * mseIndependent);
}

}  // namespace
}  // namespace pf::test
