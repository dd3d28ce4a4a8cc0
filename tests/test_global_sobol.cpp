// The global Sobol sampler (core/global_sobol_sampler.h, the scene's `sobol`): its generator matrices against
// Boost.Random's Sobol sequence; its enumeration (the samples of every pass put one point into each pixel, and
// successive passes form nets over the film, so each pixel's own film positions are stratified); that every
// sample's numbers are uniform and independent of each other over random seeds (chi-square; what keeps
// estimators unbiased), also in a later epoch; that a number depends only on its dimension, however 1D and 2D
// requests interleave (the sampler computes ahead); the independent numbers past its matrices; and what it is
// for: neighbouring pixels stratified together, which lowers the error of averages over image regions.
#include <gtest/gtest.h>

#include <boost/random/sobol.hpp>
#include <set>

#include "core/global_sobol_sampler.h"
#include "core/ld_sampler.h"
#include "core/owen_sobol.h"
#include "core/sobol_matrices.h"
#include "image/metrics.h"
#include "support/chi2.h"
#include "support/nets.h"
#include "test_mlt_common.h"

namespace pf::test {
namespace {

// The matrices against Boost's engine, which runs through the sequence in Gray-code order from index 1, so its first
// 2^m - 1 points are the points of indices 1 .. 2^m - 1, in another order.
TEST(SobolMatrices, MatchBoostRandomsSobolSequence) {
    constexpr int kPoints = 1 << 10, kDims = sobol::kMatrixDimensions;
    boost::random::sobol_engine<uint32_t, 32> engine(kDims);
    std::set<std::vector<uint32_t>> boost, ours;
    for (int i = 1; i < kPoints; ++i) {
        std::vector<uint32_t> a(kDims), b(kDims);
        for (int d = 0; d < kDims; ++d) {
            a[d] = engine();
            b[d] = sobol::reverseBits(sobol::reversedPoint(sobol::reversedColumns(d), static_cast<uint32_t>(i)));
        }
        boost.insert(std::move(a));
        ours.insert(std::move(b));
    }
    EXPECT_EQ(boost, ours);
    // The digit tables the sampler reads give the same products as the columns.
    PCG32 rng(3, 5);
    for (int k = 0; k < 20000; ++k) {
        const uint32_t i = rng.nextUInt();
        const int d = static_cast<int>(rng.nextUInt(kDims));
        ASSERT_EQ(sobol::reversedPointByDigits(sobol::reversedDigitTables(d), i),
                  sobol::reversedPoint(sobol::reversedColumns(d), i))
            << "dimension " << d << " index " << i;
    }
    // Dimensions 0 and 1 are the padded sampler's (0,2)-sequence.
    for (uint32_t i : {1u, 2u, 77u, 0xdeadbeefu}) {
        EXPECT_EQ(sobol::reversedPoint(sobol::reversedColumns(0), i), i);
        EXPECT_EQ(sobol::reversedPoint(sobol::reversedColumns(1), i), sobol::reversedSecondDimension(i));
    }
}

// The film position of sample `sample` of pixel (x, y) in units of the grid's side, and the numbers' check that
// the offset lies in the pixel.
Vec2 filmPoint(GlobalSobolSampler &s, uint64_t seed, int width, int x, int y, uint64_t sample) {
    s.start(seed, static_cast<uint64_t>(y) * width + x, sample);
    const Vec2 offset = s.next2D();
    EXPECT_TRUE(offset.x >= 0 && offset.x < 1 && offset.y >= 0 && offset.y < 1);
    const double side = std::ldexp(1.0, s.log2Side());
    return {(x + offset.x) / side, (y + offset.y) / side};
}

// On a 16 x 16 film: passes 0 .. 2^j - 1 over all pixels are one (0, 8 + j, 2)-net of the film (so each pixel's
// 2^j positions are a (0,j,2)-net of the pixel), for passes that start anywhere on a multiple of 2^j, and each
// pass's indices are one block of the sequence. On films whose sides are not the grid's (12 x 7 and 1 x 5 in a
// 16 x 16 grid), each pixel's positions are still nets.
TEST(GlobalSobolSampler, PassesAreNetsOfTheFilmAndEachPixelIsStratified) {
    GlobalSobolSampler s(16, 16);
    ASSERT_EQ(s.log2Side(), 4);
    for (uint64_t seed : {1u, 2u})
        for (int j = 0; j <= 4; ++j)
            for (uint64_t first : {uint64_t{0}, uint64_t{16} << j}) {
                std::vector<Vec2> film;
                for (uint64_t pass = first; pass < first + (uint64_t{1} << j); ++pass) {
                    std::set<uint32_t> indices;
                    for (int y = 0; y < 16; ++y)
                        for (int x = 0; x < 16; ++x) {
                            film.push_back(filmPoint(s, seed, 16, x, y, pass));
                            indices.insert(s.index() >> 8);
                        }
                    EXPECT_EQ(indices, std::set<uint32_t>{static_cast<uint32_t>(pass)});
                }
                EXPECT_TRUE(isNet(film, 8 + j)) << "seed " << seed << " passes " << first << "+" << (1 << j);
            }
    for (const auto &[w, h] : {std::pair{12, 7}, std::pair{1, 5}}) {
        GlobalSobolSampler g(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int j : {2, 5}) {
                    std::vector<Vec2> own;
                    for (uint64_t i = 0; i < (uint64_t{1} << j); ++i) {
                        g.start(3, static_cast<uint64_t>(y) * w + x, i);
                        own.push_back(g.next2D());
                    }
                    EXPECT_TRUE(isNet(own, j)) << w << "x" << h << " pixel " << x << "," << y;
                }
    }
}

// Over random seeds, one sample's numbers (its film offset, and later dimensions taken as 2D and 1D requests) are
// uniform, and pairs of them independent: 2D histograms of pairs pass a chi-square test. Covers the first
// sample, a later one, and one in the second epoch of a film whose grid leaves 2^2 passes per epoch.
TEST(GlobalSobolSampler, EachSamplesNumbersAreUniformAndIndependentOverSeeds) {
    constexpr int kBins = 16, kSeeds = 100000;
    const std::vector<double> expected(kBins * kBins, static_cast<double>(kSeeds) / (kBins * kBins));
    const auto bin = [](double u) { return std::min(kBins - 1, static_cast<int>(u * kBins)); };
    struct Case {
        int width, height, x, y;
        uint64_t sample;
    };
    const Case cases[] = {{64, 48, 5, 9, 0}, {64, 48, 63, 47, 37}, {1 << 15, 2, 123, 1, 6}};
    for (const Case &c : cases) {
        GlobalSobolSampler s(c.width, c.height);
        std::vector<double> offset(kBins * kBins), offsetAndLater(kBins * kBins), later(kBins * kBins),
            far(kBins * kBins);
        for (int seed = 0; seed < kSeeds; ++seed) {
            s.start(static_cast<uint64_t>(seed) + 1000, static_cast<uint64_t>(c.y) * c.width + c.x, c.sample);
            const Vec2 o = s.next2D(), a = s.next2D();
            const double u = s.next1D();
            for (int d = 5; d < 40; ++d) s.next1D();
            const Vec2 b = s.next2D();
            offset[bin(o.x) * kBins + bin(o.y)] += 1;
            offsetAndLater[bin(o.x) * kBins + bin(a.y)] += 1;
            later[bin(a.x) * kBins + bin(u)] += 1;
            far[bin(u) * kBins + bin(b.y)] += 1;
        }
        for (const auto &[name, histogram] : {std::pair{"film offset", &offset},
                                              {"offset x and dimension 3", &offsetAndLater},
                                              {"dimensions 2 and 4", &later},
                                              {"dimensions 4 and 41", &far}}) {
            const Chi2Result r = chi2Histogram(*histogram, expected, 0.01, 4 * 3);
            EXPECT_TRUE(r.passed) << name << ", film " << c.width << "x" << c.height << " sample " << c.sample << ": "
                                  << r.report;
        }
    }
}

// A number depends on (seed, pixel, sample, dimension) alone: a sampler restarted over samples of two pixels and
// consumed in random interleavings of 1D and 2D requests gives the numbers of a fresh sampler read one dimension
// at a time. Past the matrices' dimensions the numbers are the sample's independent stream.
TEST(GlobalSobolSampler, NumbersDependOnlyOnTheirDimension) {
    GlobalSobolSampler reused(40, 30);
    PCG32 rng(7, 1);
    for (int round = 0; round < 300; ++round) {
        const uint64_t pixel = 100 + rng.nextUInt(2), sample = rng.nextUInt(50);
        reused.start(9, pixel, sample);
        std::vector<double> got;
        for (int k = static_cast<int>(rng.nextUInt(20)); k > 0; --k) {
            if (rng.nextUInt(2)) {
                got.push_back(reused.next1D());
            } else {
                const Vec2 p = reused.next2D();
                got.push_back(p.x);
                got.push_back(p.y);
            }
        }
        GlobalSobolSampler fresh(40, 30);
        fresh.start(9, pixel, sample);
        for (size_t d = 0; d < got.size(); ++d) ASSERT_EQ(fresh.next1D(), got[d]) << "dimension " << d;
    }
    GlobalSobolSampler s(40, 30);
    s.start(3, 77, 5);
    for (int d = 0; d < sobol::kMatrixDimensions; ++d) s.next1D();
    IndependentSampler independent(3, 77, 5);
    EXPECT_EQ(s.next1D(), independent.next1D());
    const Vec2 p = s.next2D(), q = independent.next2D();
    EXPECT_EQ(p.x, q.x);
    EXPECT_EQ(p.y, q.y);
    // Another seed, pixel or sample gives other numbers.
    const auto first = [](uint64_t seed, uint64_t pixel, uint64_t sample) {
        GlobalSobolSampler g(40, 30);
        g.start(seed, pixel, sample);
        g.next2D();
        return g.next1D();
    };
    EXPECT_NE(first(3, 77, 5), first(4, 77, 5));
    EXPECT_NE(first(3, 77, 5), first(3, 78, 5));
    EXPECT_NE(first(3, 77, 5), first(3, 77, 6));
}

// Sampler::startPart: part p begins at dimension p * kDimensionsPerPart whatever part 0 consumed below that, so
// its numbers are those of that dimension (a fresh sampler read one dimension at a time); where part 0 ran past
// it, the part continues right after (no dimension is drawn twice in a sample).
TEST(GlobalSobolSampler, PartsStartAtFixedDimensions) {
    constexpr uint32_t kBase = GlobalSobolSampler::kDimensionsPerPart;
    PCG32 rng(5, 2);
    for (int round = 0; round < 100; ++round) {
        const uint64_t pixel = rng.nextUInt(1200), sample = rng.nextUInt(64);
        const uint32_t before = 2 + rng.nextUInt(2 * kBase);  // dimensions part 0 takes (one past kBase at most 2x)
        GlobalSobolSampler s(40, 30), fresh(40, 30);
        s.start(9, pixel, sample);
        for (uint32_t d = 0; d < before; ++d) s.next1D();
        s.startPart(1);
        const Vec2 p = s.next2D();
        fresh.start(9, pixel, sample);
        for (uint32_t d = 0; d < std::max(before, kBase); ++d) fresh.next1D();
        ASSERT_EQ(p.x, fresh.next1D()) << "part 0 took " << before;
        ASSERT_EQ(p.y, fresh.next1D()) << "part 0 took " << before;
    }
}

// What the sequence is for. One sample per pixel of a smooth integrand of a 2D request, averaged over an 8 x 8
// block of pixels: the global sequence stratifies the block's 64 points together (with their film positions), the
// padded one (each pixel's own sequence) leaves them independent. Over 400 seeds the block mean's squared error
// falls far below the padded sampler's, which is that of 64 independent points.
TEST(GlobalSobolSampler, StratifiesNeighbouringPixelsTogether) {
    constexpr int kSeeds = 400, kSide = 64;
    const auto f = [](const Vec2 &u) { return u.x * u.y + std::sin(3 * u.x) + u.y * u.y; };
    const double exact = 0.25 + (1 - std::cos(3.0)) / 3 + 1.0 / 3;
    const auto blockError = [&](PixelSampler &s) {
        double mse = 0;
        for (uint64_t seed = 0; seed < kSeeds; ++seed) {
            double mean = 0;
            for (int y = 16; y < 24; ++y)
                for (int x = 8; x < 16; ++x) {
                    s.start(seed, static_cast<uint64_t>(y) * kSide + x, 3);
                    s.next2D();
                    mean += f(s.next2D()) / 64;
                }
            mse += (mean - exact) * (mean - exact) / kSeeds;
        }
        return mse;
    };
    GlobalSobolSampler global(kSide, kSide);
    LowDiscrepancySampler padded;
    const double g = blockError(global), p = blockError(padded);
    std::printf("8x8 block mean of a smooth integrand, 1 spp: MSE %.3g (global) against %.3g (padded), %.1fx\n", g, p,
                p / g);
    EXPECT_LT(g, 0.2 * p);
}

// The path tracer on the Cornell box at 16 samples per pixel with a box filter, its `sobol` sampler with layout
// "image" against the default (each pixel's padded sequence), each over six seeds and against one reference: over
// 8 x 8 blocks the global sequence's relMSE is clearly lower (0.71x when this test was written; a sequence that
// left pixels independent would come out level). The per-pixel figures are printed too: there the two trade
// places with the sample count (README, "Samplers").
TEST(GlobalSobolSampler, LowersTheErrorOfBlockMeansOnTheCornellBox) {
    constexpr int kRes = 64, kSpp = 16, kSeeds = 6, kBlock = 8;
    const auto global = loadMLTTestScene("cornell-box-imagesobol", kRes, kSpp);
    const auto padded = loadMLTTestScene("cornell-box", kRes, kSpp);
    ASSERT_TRUE(global->sensor().sampleSequence().acrossPixels);
    ASSERT_FALSE(padded->sensor().sampleSequence().acrossPixels);
    ASSERT_TRUE(padded->sensor().sampleSequence().lowDiscrepancy);
    const auto render = [](const Scene &scene, int64_t spp, uint64_t seed) {
        return renderTestImage(scene, "path", spp, seed);
    };
    const Bitmap reference = render(*padded, 1024, 99);
    const Bitmap referenceBlocks = blockMeans(reference, kBlock);
    double pixelsGlobal = 0, pixelsPadded = 0, blocksGlobal = 0, blocksPadded = 0;
    for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
        const Bitmap a = render(*global, kSpp, seed), b = render(*padded, kSpp, seed);
        pixelsGlobal += computeMetrics(a, reference).relMse / kSeeds;
        pixelsPadded += computeMetrics(b, reference).relMse / kSeeds;
        blocksGlobal += computeMetrics(blockMeans(a, kBlock), referenceBlocks).relMse / kSeeds;
        blocksPadded += computeMetrics(blockMeans(b, kBlock), referenceBlocks).relMse / kSeeds;
    }
    std::printf(
        "cornell-box %d², path at %d spp over %d seeds, image layout against pixel layout: pixels relMSE %.4g "
        "against %.4g (%.2fx), %dx%d blocks %.4g against %.4g (%.2fx)\n",
        kRes, kSpp, kSeeds, pixelsGlobal, pixelsPadded, pixelsPadded / pixelsGlobal, kBlock, kBlock, blocksGlobal,
        blocksPadded, blocksPadded / blocksGlobal);
    EXPECT_LT(blocksGlobal, 0.85 * blocksPadded);
}

// Unbiased under a sample budget: `path` and `bdpt` on the Cornell box with layout "image" agree with BDPT on the
// default (padded) sequence, block by block over 16 independent renders at 16 spp (test_mlt_common.h's thresholds;
// the same cases under `--time` are in test_time_budget, against a reference of their own layout).
TEST(GlobalSobolSampler, PathAndBDPTAgreeWithBDPTAtASampleBudget) {
    const ConvergenceSetup s;
    const auto global = loadMLTTestScene("cornell-box-imagesobol", s.res, 4);
    const auto padded = loadMLTTestScene("cornell-box", s.res, 4);
    const BlockStats &reference = bdptReference("cornell-box", *padded, s.block, s.seeds, s.referenceSpp, 0);
    for (const std::string type : {"path", "bdpt"}) {
        const BlockStats image = blockStats(*global, *makeTestIntegrator(*global, type, {}), s.block, s.seeds, 16, 2);
        const std::string what = "cornell-box, sobol layout image, " + type + " --spp 16";
        printAgreement(reference, image, what);
        expectBlocksAgree(reference, image, s.sigmas, s.maxMedianError, s.maxImageError, what);
    }
}

}  // namespace
}  // namespace pf::test
