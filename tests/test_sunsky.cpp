// Mitsuba 0.6's daylight emitters (sky, sun, sunsky): the Hosek-Wilkie model against the reference code's
// check values (data/sunsky/hosek_check_*.txt), the sky's angles, scale, stretch and extension, the solar
// position algorithm against Reda & Andreas' published test case, the sun's radiance, chi-square tests of
// the sky's and the sun's direction sampling (next-event estimation and emission), the parameters, and
// `bdpt` against `path` on a scene lit by sunsky.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "emitter/environment.h"
#include "emitter/sunsky/daylight_emitter.h"
#include "emitter/sunsky/daylight_params.h"
#include "emitter/sunsky/hosek_wilkie.h"
#include "emitter/sunsky/sky_model.h"
#include "emitter/sunsky/solar_position.h"
#include "emitter/sunsky/sun_radiance.h"
#include "emitter/sunsky/tables.h"
#include "support/emitter_checks.h"
#include "test_pssmlt_common.h"

namespace pf::test {
namespace {

using sunsky::SphericalCoordinates;

constexpr int kChi2Tests = 8;  // chi-square tests in this file, for the multiple-test correction

// ---- data files ----

std::vector<std::vector<double>> readTable(const std::string &name) {
    const std::string path = std::string(PATHFARM_SOURCE_DIR) + "/data/sunsky/" + name;
    std::ifstream in(path);
    EXPECT_TRUE(in.good()) << "cannot read " << path;
    std::vector<std::vector<double>> rows;
    for (std::string line; std::getline(in, line);) {
        std::istringstream s(line);
        std::vector<double> row;
        for (double v; s >> v;) row.push_back(v);
        if (!row.empty()) rows.push_back(row);
    }
    return rows;
}

std::vector<double> flatten(const std::vector<std::vector<double>> &rows) {
    std::vector<double> out;
    for (const auto &r : rows) out.insert(out.end(), r.begin(), r.end());
    return out;
}

// A dataset read from the text tables (the XYZ and spectral ones are not compiled into pathfarm).
struct TextDataset {
    std::vector<double> coefficients, radiances;
    int channels;
    sunsky::HosekDataset view() const { return {coefficients.data(), radiances.data(), channels}; }
};

TextDataset textDataset(const std::string &kind, int channels) {
    return {flatten(readTable("hosek_" + kind + "_coeffs.txt")), flatten(readTable("hosek_" + kind + "_radiance.txt")),
            channels};
}

// Largest relative error of the model against one check file; every value must be within 1e-5.
double checkAgainst(const sunsky::HosekDataset &data, const std::string &checkFile) {
    const auto rows = readTable(checkFile);
    EXPECT_EQ(rows.size(), 10u);
    double worst = 0;
    for (const auto &row : rows) {
        EXPECT_EQ(static_cast<int>(row.size()), 5 + data.channels);
        const double turbidity = row[0], albedo = row[1], elevation = row[2], theta = row[3], gamma = row[4];
        for (int c = 0; c < data.channels; ++c) {
            const double value = sunsky::HosekChannel(data, c, turbidity, albedo, elevation).radiance(theta, gamma);
            const double expected = row[5 + c], rel = std::abs(value - expected) / std::abs(expected);
            EXPECT_LT(rel, 1e-5) << checkFile << ": T " << turbidity << ", albedo " << albedo << ", elevation "
                                 << elevation << ", theta " << theta << ", gamma " << gamma << ", channel " << c << ": "
                                 << value << " vs " << expected;
            worst = std::max(worst, rel);
        }
    }
    return worst;
}

// ---- Hosek-Wilkie model ----

TEST(HosekWilkie, CompiledTablesAreTheTextTables) {
    const TextDataset rgb = textDataset("rgb", 3);
    ASSERT_EQ(rgb.coefficients.size(), std::size(sunsky::kHosekRGBCoeffs));
    ASSERT_EQ(rgb.radiances.size(), std::size(sunsky::kHosekRGBRadiance));
    for (size_t i = 0; i < rgb.coefficients.size(); ++i) ASSERT_EQ(rgb.coefficients[i], sunsky::kHosekRGBCoeffs[i]);
    for (size_t i = 0; i < rgb.radiances.size(); ++i) ASSERT_EQ(rgb.radiances[i], sunsky::kHosekRGBRadiance[i]);
    const auto expectTable = [](const std::string &file, const double *wavelengths, const double *values, size_t n) {
        const auto rows = readTable(file);
        ASSERT_EQ(rows.size(), n) << file;
        for (size_t i = 0; i < n; ++i) {
            EXPECT_EQ(rows[i][0], wavelengths[i]) << file;
            EXPECT_EQ(rows[i][1], values[i]) << file;
        }
    };
    expectTable("sun_k_o.txt", sunsky::kSunKOWavelengths, sunsky::kSunKOValues, std::size(sunsky::kSunKOValues));
    expectTable("sun_k_g.txt", sunsky::kSunKGWavelengths, sunsky::kSunKGValues, std::size(sunsky::kSunKGValues));
    expectTable("sun_k_wa.txt", sunsky::kSunKWaWavelengths, sunsky::kSunKWaValues, std::size(sunsky::kSunKWaValues));
    expectTable("sun_solar_radiance.txt", sunsky::kSunSolarWavelengths, sunsky::kSunSolarValues,
                std::size(sunsky::kSunSolarValues));
}

TEST(HosekWilkie, CheckValuesOfTheReferenceCode) {
    const double rgb = checkAgainst(sunsky::hosekRGB(), "hosek_check_rgb.txt");
    const TextDataset xyz = textDataset("xyz", 3), spectral = textDataset("spectral", 11);
    const double xyzErr = checkAgainst(xyz.view(), "hosek_check_xyz.txt");
    const double spectralErr = checkAgainst(spectral.view(), "hosek_check_spectral.txt");
    std::printf(
        "Hosek-Wilkie vs reference code, largest relative error: RGB %.2e (30 values), XYZ %.2e (30), "
        "spectral %.2e (110)\n",
        rgb, xyzErr, spectralErr);
}

// ---- sky radiance ----

sunsky::SkyParameters skyParameters(double turbidity, double albedo, double sunElevation, double sunAzimuth) {
    sunsky::SkyParameters p;
    p.sun = {0.5 * kPi - sunElevation, sunAzimuth};
    p.turbidity = turbidity;
    p.albedo = Spectrum(albedo);
    return p;
}

// The two check rows whose (theta, gamma) a real direction can have, through the sky's own angle
// computation: the sky's RGB is the model's divided by 106.856980 (Mitsuba's sum of CIE y-bar).
TEST(SkyModel, CheckValuesThroughDirections) {
    const auto rows = readTable("hosek_check_rgb.txt");
    int checked = 0;
    double worst = 0;
    for (const auto &row : rows) {
        const double turbidity = row[0], albedo = row[1], elevation = row[2], theta = row[3], gamma = row[4];
        const double sunTheta = 0.5 * kPi - elevation, sunPhi = 1.0;
        const double cosDphi =
            (std::cos(gamma) - std::cos(theta) * std::cos(sunTheta)) / (std::sin(theta) * std::sin(sunTheta));
        if (!(std::abs(cosDphi) <= 1)) continue;
        const sunsky::SkyModel sky(skyParameters(turbidity, albedo, elevation, sunPhi));
        const Spectrum L = sky.radiance({theta, sunPhi + std::acos(cosDphi)});
        for (int c = 0; c < 3; ++c) {
            const double expected = row[5 + c] / 106.856980, rel = std::abs(L[c] - expected) / expected;
            EXPECT_LT(rel, 1e-5) << "row T " << turbidity << " channel " << c;
            worst = std::max(worst, rel);
        }
        ++checked;
    }
    EXPECT_EQ(checked, 2);
    std::printf("sky radiance through directions, %d check rows: largest relative error %.2e\n", checked, worst);
}

// Directions over the whole upper hemisphere for several turbidities, albedos and suns: the sky evaluates
// the model at the direction's zenith angle and at its angle to the sun, times scale, per channel.
TEST(SkyModel, DirectionsTurbiditiesAndAlbedos) {
    const sunsky::HosekDataset rgb = sunsky::hosekRGB();
    PCG32 rng(3, 4);
    int n = 0;
    for (const double turbidity : {1.0, 2.2, 3.0, 5.5, 9.9, 10.0})
        for (const Spectrum albedo : {Spectrum(0.0), Spectrum(0.2), Spectrum(1.0, 0.5, 0.1)})
            for (const double sunTheta : {0.1, 0.7, 1.3, 1.55}) {
                sunsky::SkyParameters p;
                p.sun = {sunTheta, 2 * kPi * rng.nextDouble()};
                p.turbidity = turbidity;
                p.albedo = albedo;
                p.scale = 1.7;
                const sunsky::SkyModel sky(p);
                const Vec3 sunDir = sunsky::toSphere(p.sun);
                for (int k = 0; k < 20; ++k) {
                    const SphericalCoordinates d{0.5 * kPi * rng.nextDouble(), 2 * kPi * rng.nextDouble()};
                    const double gamma = std::acos(clamp(dot(sunsky::toSphere(d), sunDir), -1.0, 1.0));
                    if (gamma < 1e-3) continue;  // acos has too few digits there for a 1e-9 comparison
                    const Spectrum L = sky.radiance(d);
                    for (int c = 0; c < 3; ++c) {
                        const double expected =
                            std::max(0.0, sunsky::HosekChannel(rgb, c, turbidity, albedo[c], 0.5 * kPi - sunTheta)
                                              .radiance(d.theta, gamma)) /
                            106.856980 * 1.7;
                        EXPECT_NEAR(L[c], expected, 1e-9 * expected);
                    }
                    ++n;
                }
            }
    EXPECT_GT(n, 1300);
}

TEST(SkyModel, HorizonStretchAndExtend) {
    sunsky::SkyParameters p = skyParameters(3, 0.2, 0.6, 1.0);
    const sunsky::SkyModel plain(p);
    EXPECT_TRUE(plain.radiance({0.5 * kPi + 1e-3, 0.3}).isBlack());
    EXPECT_FALSE(plain.radiance({0.5 * kPi - 1e-3, 0.3}).isBlack());

    // stretch divides the zenith angle the model sees: a direction at 1.4 with stretch 2 sees 0.7.
    p.stretch = 2;
    const sunsky::SkyModel stretched(p);
    EXPECT_FALSE(stretched.radiance({2.0, 0.3}).isBlack());
    const SphericalCoordinates sun = p.sun;
    const Spectrum a = stretched.radiance({1.4, 0.3});
    sunsky::SkyParameters q = p;
    q.stretch = 1;
    const Spectrum b = sunsky::SkyModel(q).radiance({0.7, 0.3});
    EXPECT_NEAR(a.g, b.g, 1e-12 * b.g);
    EXPECT_EQ(sun.theta, p.sun.theta);

    // extend continues the horizon downwards and fades it with smoothstep(2 - 2 theta / pi) to the nadir.
    p.stretch = 1;
    p.extend = true;
    const sunsky::SkyModel extended(p);
    const Spectrum horizon = extended.radiance({0.5 * kPi - 1e-4, 0.3});
    const Spectrum below = extended.radiance({0.75 * kPi, 0.3});
    EXPECT_NEAR(below.g, horizon.g * 0.5, 1e-3 * horizon.g);  // smoothstep(0.5) = 0.5
    EXPECT_TRUE(extended.radiance({kPi, 0.3}).isBlack());
}

// The `sky` plugin shows the map of the model at pixel centres, through toWorld.
TEST(SkyEmitter, MapPixelsThroughToWorld) {
    Properties p = props(ObjectKind::Emitter, "sky");
    const Transform toWorld = Transform::rotate(Vec3(1, 0, 0), 90) * Transform::rotate(Vec3(0, 1, 0), 30);
    setTransform(p, "toWorld", toWorld);
    p.set("resolution", Properties::Type::Integer, int64_t(64), kEmitterTestLoc);
    setFloat(p, "turbidity", 4.5);
    setFloat(p, "scale", 2.0);
    const auto e = makeEmitter(p);
    EXPECT_TRUE(e->isEnvironment());
    sunsky::SkyParameters sp = skyParameters(4.5, 0.2, 0, 0);
    sp.sun = sunsky::solarPosition({});
    sp.scale = 2.0;
    const sunsky::SkyModel sky(sp);
    for (const auto &[x, y] : {std::pair{0, 0}, {5, 3}, {16, 15}, {40, 10}, {63, 31}, {30, 20}}) {
        const SphericalCoordinates c{kPi * (y + 0.5) / 32, 2 * kPi * (x + 0.5) / 64};
        const Spectrum expected = sky.radiance(c);
        const Spectrum seen = e->evalEnvironment(Ray(Vec3(0.0), toWorld.vector(sunsky::toSphere(c))));
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(seen[k], expected[k], 1e-6 * expected[k] + 1e-30);
    }
}

// ---- sun position ----

// Reda & Andreas, "Solar Position Algorithm for Solar Radiation Applications", NREL/TP-560-34302 (2004/2008),
// its worked example: 17 October 2003, 12:30:30 local time (UTC-7), 39.742476 N, 105.1786 W, 1830.14 m, 820 mbar,
// 11 C: topocentric zenith 50.11162 degrees (refraction included), azimuth 194.34024 degrees (from north,
// eastward). Mitsuba's PSA ignores refraction and elevation; its stated accuracy is 0.5' = 0.0083 degrees.
TEST(SolarPosition, RedaAndreasTestCase) {
    sunsky::DateTimeLocation when;
    when.year = 2003;
    when.month = 10;
    when.day = 17;
    when.hour = 12;
    when.minute = 30;
    when.second = 30;
    when.timezone = -7;
    when.latitude = 39.742476;
    when.longitude = -105.1786;
    const SphericalCoordinates sun = sunsky::solarPosition(when);
    const double zenith = radToDeg(sun.theta), azimuth = radToDeg(sun.phi);
    // SPA's atmospheric refraction correction (Reda & Andreas, eq. 42) at the test's pressure and temperature, so that
    // the geometric zenith of PSA can be compared with SPA's apparent one.
    const double e0 = 90.0 - zenith;
    const double refraction =
        (820.0 / 1010.0) * (283.0 / (273.0 + 11.0)) * 1.02 / (60.0 * std::tan(degToRad(e0 + 10.3 / (e0 + 5.11))));
    std::printf(
        "PSA for the SPA test case: zenith %.5f deg (SPA 50.11162; %.5f with SPA's refraction of %.5f deg: "
        "difference %.5f), azimuth %.5f deg (SPA 194.34024: difference %.5f)\n",
        zenith, zenith - refraction, refraction, zenith - refraction - 50.11162, azimuth, azimuth - 194.34024);
    EXPECT_NEAR(azimuth, 194.34024, 0.0083);
    EXPECT_NEAR(zenith - refraction, 50.11162, 0.0083);
    EXPECT_NEAR(zenith, 50.11162, 0.02);  // what the emitter uses: no refraction
}

// Mitsuba's defaults (Tokyo, 10 July 2010, 15:00, UTC+9): the sun stands west-south-west, 46 degrees high.
TEST(SolarPosition, MitsubaDefaults) {
    const SphericalCoordinates sun = sunsky::solarPosition({});
    EXPECT_NEAR(radToDeg(sun.theta), 43.921, 1e-3);
    EXPECT_NEAR(radToDeg(sun.phi), 265.752, 1e-3);
    const Vec3 d = sunsky::toSphere(sun);
    EXPECT_NEAR(d.x, -0.6918, 1e-4);
    EXPECT_NEAR(d.y, 0.7203, 1e-4);
    EXPECT_NEAR(d.z, 0.0514, 1e-4);
    // The frame: azimuth 90 degrees is east (+X), 180 south (+Z); fromSphere inverts toSphere.
    EXPECT_NEAR(sunsky::toSphere({0.5 * kPi, 0.5 * kPi}).x, 1.0, 1e-15);
    EXPECT_NEAR(sunsky::toSphere({0.5 * kPi, kPi}).z, 1.0, 1e-15);
    const SphericalCoordinates back = sunsky::fromSphere(d);
    EXPECT_NEAR(back.theta, sun.theta, 1e-14);
    EXPECT_NEAR(back.phi, sun.phi, 1e-14);
}

// ---- sun radiance ----

TEST(SunRadiance, ValuesAndTrends) {
    const double theta = degToRad(43.92);
    const Spectrum L = sunsky::sunRadiance(theta, 3);
    // An independent transcription (Python, the same 5 nm CIE table) of Preetham's attenuation gives these.
    EXPECT_NEAR(L.r, 19252.26, 0.5);
    EXPECT_NEAR(L.g, 15863.19, 0.5);
    EXPECT_NEAR(L.b, 12871.03, 0.5);
    // Times the disk's solid angle, about 1 W m^-2 nm^-1 of direct irradiance: a clear afternoon.
    const double irradiance = L.luminance() * sunsky::coneSolidAngle(degToRad(sunsky::kSunHalfAngleDegrees));
    std::printf("sun at zenith 43.92 deg, turbidity 3: RGB radiance (%.1f, %.1f, %.1f), irradiance Y %.3f\n", L.r, L.g,
                L.b, irradiance);
    EXPECT_GT(irradiance, 0.8);
    EXPECT_LT(irradiance, 1.6);
    // A low sun is dimmer and redder; haze dims it.
    const Spectrum low = sunsky::sunRadiance(degToRad(85), 3);
    EXPECT_LT(low.luminance(), 0.5 * L.luminance());
    EXPECT_GT(low.r / low.b, 2.0 * L.r / L.b);
    EXPECT_LT(sunsky::sunRadiance(theta, 8).luminance(), 0.8 * L.luminance());
    // The disk's solid angle: half of Mitsuba's 0.5358 degrees as the cone's half-angle.
    EXPECT_NEAR(sunsky::coneSolidAngle(degToRad(sunsky::kSunHalfAngleDegrees)), 6.86830e-5, 1e-9);
}

// ---- sampling ----

// Chi-square of directions in a cap of half-angle capAngle around `axis`: rings of equal solid angle times
// sectors of azimuth, the expected counts from the pdf by a midpoint rule per cell (fine across the rings, where
// the disk's edge cuts them),
// and one more cell for everything outside the cap. For a density as narrow as the sun's.
Chi2Result capChi2(const DirectionSampler &sample, const DirectionPdf &pdf, const Vec3 &axis, double capAngle,
                   int rings, int sectors, uint64_t seed = 41, int sampleCount = 200000) {
    constexpr int ringRes = 256, sectorRes = 4;
    const Frame frame(axis);
    const double oneMinusCosCap = 2 * std::pow(std::sin(0.5 * capAngle), 2);
    const int cells = rings * sectors;
    std::vector<double> observed(cells + 1, 0.0), expected(cells + 1, 0.0);
    PCG32 rng(seed, 7);
    for (int i = 0; i < sampleCount; ++i) {
        Vec3 d;
        if (!sample(rng, d)) continue;
        const Vec3 l = frame.toLocal(d);
        const double oneMinusCos = l.x * l.x + l.y * l.y;  // ~ 1 - cos for small angles; exact below
        const double u = (oneMinusCos / (1 + std::sqrt(std::max(0.0, 1 - oneMinusCos)))) / oneMinusCosCap;
        if (l.z <= 0 || u >= 1) {
            observed[cells] += 1;
            continue;
        }
        double phi = std::atan2(l.y, l.x);
        if (phi < 0) phi += 2 * kPi;
        const int ring = std::min(int(u * rings), rings - 1),
                  sector = std::min(int(phi / (2 * kPi) * sectors), sectors - 1);
        observed[ring * sectors + sector] += 1;
    }
    double inside = 0;
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < sectors; ++s) {
            double sum = 0;
            for (int i = 0; i < ringRes; ++i)
                for (int j = 0; j < sectorRes; ++j) {
                    const double u = (r + (i + 0.5) / ringRes) / rings,
                                 phi = 2 * kPi * (s + (j + 0.5) / sectorRes) / sectors;
                    const double oneMinusCos = u * oneMinusCosCap, sinA = std::sqrt(oneMinusCos * (2 - oneMinusCos));
                    sum += pdf(frame.toWorld(Vec3(sinA * std::cos(phi), sinA * std::sin(phi), 1 - oneMinusCos)));
                }
            // Each cell spans oneMinusCosCap / rings in (1 - cos) and 2 pi / sectors in azimuth.
            const double mass = sum / (ringRes * sectorRes) * oneMinusCosCap / rings * 2 * kPi / sectors;
            expected[r * sectors + s] = mass * sampleCount;
            inside += mass;
        }
    expected[cells] = std::max(0.0, 1 - inside) * sampleCount;
    Chi2Result result = chi2Histogram(observed, expected, 0.01, kChi2Tests);
    result.integratedMass = inside;
    return result;
}

// Sampler and density of sampleDirect from ref, and of sampleDirection (emission) at a sampled position.
DirectionSampler directSampler(const Emitter &e, const Vec3 &ref) {
    return [&e, ref](PCG32 &rng, Vec3 &d) {
        DirectSample ds(ref, Vec3(0.0));
        e.sampleDirect(ds, {rng.nextDouble(), rng.nextDouble()});
        d = ds.d;
        return ds.pdf > 0;
    };
}
DirectionPdf directPdf(const Emitter &e, const Vec3 &ref) {
    return [&e, ref](const Vec3 &d) {
        DirectSample ds(ref, Vec3(0.0));
        if (!environmentHit(e, ref, d, ds)) return 0.0;
        return e.pdfDirect(ds);
    };
}

Properties sunProperties(const std::string &plugin, const Transform &toWorld, double radiusScale) {
    Properties p = props(ObjectKind::Emitter, plugin);
    setTransform(p, "toWorld", toWorld);
    setFloat(p, "sunRadiusScale", radiusScale);
    setFloat(p, "hour", 11.5);
    return p;
}

std::shared_ptr<Emitter> configured(std::shared_ptr<Emitter> e) {
    dynamic_cast<InfiniteEmitter &>(*e).setBoundingSphere(Vec3(0, 1, 0), 2.0);
    return e;
}

Vec3 worldSunDirection(const Transform &toWorld, double hour) {
    sunsky::DateTimeLocation when;
    when.hour = hour;
    return normalize(toWorld.vector(sunsky::toSphere(sunsky::solarPosition(when))));
}

const Transform kToWorld = Transform::rotate(Vec3(0.3, 1, 0.2), 70);

TEST(SkyEmitter, SamplingChiSquare) {
    Properties p = props(ObjectKind::Emitter, "sky");
    setTransform(p, "toWorld", kToWorld);
    p.set("resolution", Properties::Type::Integer, int64_t(64), kEmitterTestLoc);
    setFloat(p, "hour", 17.5);  // a low sun: a bright band near the horizon
    const auto e = configured(makeEmitter(p));
    const Vec3 ref(0.2, 0.8, -0.3);
    auto hit = [&](const Vec3 &o, const Vec3 &d, DirectSample &ds) { return environmentHit(*e, o, d, ds); };
    const auto direct = directChi2(*e, ref, hit, emitterChi2Options(kChi2Tests, 32, 32, 40));
    EXPECT_TRUE(direct.passed) << direct.report;
    EXPECT_NEAR(direct.integratedMass, 1.0, 2e-3);
    PositionSample ps;
    e->samplePosition(ps, {0.4, 0.1});
    // Another seed: with the same one, emission would draw the mirror images of the same directions.
    Chi2Options emissionOptions = emitterChi2Options(kChi2Tests, 32, 32, 40);
    emissionOptions.seed = 2;
    const auto emitted = emissionChi2(*e, ps, emissionOptions);
    EXPECT_TRUE(emitted.passed) << emitted.report;
    std::printf("sky sampling chi-square: p = %.3f (next-event), p = %.3f (emission)\n", direct.pValue, emitted.pValue);
}

TEST(SunEmitter, SamplingChiSquareInTheDisk) {
    for (const double radiusScale : {1.0, 4.0}) {
        const auto e = configured(makeEmitter(sunProperties("sun", kToWorld, radiusScale)));
        const Vec3 sunDir = worldSunDirection(kToWorld, 11.5), ref(0.2, 0.8, -0.3);
        const double halfAngle = degToRad(sunsky::kSunHalfAngleDegrees) * radiusScale;
        // The cap reaches 1.3 times past the disk, so that the edge of the density is tested too.
        auto r = capChi2(directSampler(*e, ref), directPdf(*e, ref), sunDir, 1.3 * halfAngle, 12, 12);
        EXPECT_TRUE(r.passed) << r.report;
        EXPECT_NEAR(r.integratedMass, 1.0, 2e-3);
        PositionSample ps;
        e->samplePosition(ps, {0.3, 0.6});
        const auto emitted = capChi2(
            [&](PCG32 &rng, Vec3 &d) {
                DirectionSample ds;
                e->sampleDirection(ds, ps, {rng.nextDouble(), rng.nextDouble()});
                d = ds.d;
                return ds.pdf > 0;
            },
            [&](const Vec3 &d) {
                DirectionSample ds;
                ds.d = d;
                return e->pdfDirection(ds, ps);
            },
            -sunDir, 1.3 * halfAngle, 12, 12, 42);
        EXPECT_TRUE(emitted.passed) << emitted.report;
        std::printf("sun (sunRadiusScale %.0f) sampling chi-square: p = %.3f (next-event), p = %.3f (emission)\n",
                    radiusScale, r.pValue, emitted.pValue);
    }
}

// sunsky: the mixture of the sky map and the disk, on the whole sphere with a widened disk, and in the disk
// with the real one.
TEST(SunSkyEmitter, SamplingChiSquare) {
    Properties p = sunProperties("sunsky", kToWorld, 30);
    p.set("resolution", Properties::Type::Integer, int64_t(64), kEmitterTestLoc);
    const auto wide = configured(makeEmitter(p));
    const Vec3 ref(0.2, 0.8, -0.3);
    auto hit = [&](const Vec3 &o, const Vec3 &d, DirectSample &ds) { return environmentHit(*wide, o, d, ds); };
    const auto r = directChi2(*wide, ref, hit, emitterChi2Options(kChi2Tests, 32, 32, 40));
    EXPECT_TRUE(r.passed) << r.report;

    const auto e = configured(makeEmitter(sunProperties("sunsky", kToWorld, 1)));
    const auto &daylight = dynamic_cast<const sunsky::DaylightEmitter &>(*e);
    const Vec3 sunDir = worldSunDirection(kToWorld, 11.5);
    const double halfAngle = degToRad(sunsky::kSunHalfAngleDegrees);
    const auto cap = capChi2(directSampler(*e, ref), directPdf(*e, ref), sunDir, 1.3 * halfAngle, 8, 8);
    EXPECT_TRUE(cap.passed) << cap.report;
    // The cap holds the sun's share of the samples, and a sliver of sky.
    EXPECT_NEAR(cap.integratedMass, daylight.sunProbability(), 1e-3);
    std::printf(
        "sunsky sampling chi-square: p = %.3f (whole sphere, 8 degree disk), p = %.3f (real disk); "
        "sun picked with probability %.3f\n",
        r.pValue, cap.pValue, daylight.sunProbability());
    EXPECT_GT(daylight.sunProbability(), 0.5);
    EXPECT_LT(daylight.sunProbability(), 0.95);
}

TEST(SunSkyEmitter, PowerAndSplit) {
    Properties p = sunProperties("sunsky", kToWorld, 1);
    p.set("resolution", Properties::Type::Integer, int64_t(128), kEmitterTestLoc);
    const auto e = configured(makeEmitter(p));
    expectLightTracingPower(*e, 400000);
    expectDirectMatchesSplit(*e, {Vec3(0.2, 0.8, -0.3), Vec3(0, 1, 0)});
    // The sun's part of the power is its irradiance over the entry disk: L_sun * Omega * pi R^2.
    const double theta = sunsky::solarPosition([] {
                             sunsky::DateTimeLocation w;
                             w.hour = 11.5;
                             return w;
                         }())
                             .theta;
    const double sunPower = sunsky::sunRadiance(theta, 3).luminance() *
                            sunsky::coneSolidAngle(degToRad(sunsky::kSunHalfAngleDegrees)) * kPi * 4.0;
    const auto &daylight = dynamic_cast<const sunsky::DaylightEmitter &>(*e);
    EXPECT_NEAR(daylight.sunProbability(), sunPower / e->power().luminance(), 1e-9);
}

// ---- parameters ----

TEST(SunSkyParameters, SunDirectionAndConflicts) {
    Properties p = props(ObjectKind::Emitter, "sunsky");
    const Vec3 d = normalize(Vec3(1, 2, 0.5));
    p.set("sunDirection", Properties::Type::Vector, d, kEmitterTestLoc);
    setTransform(p, "toWorld", kToWorld);
    const SphericalCoordinates local = sunsky::readSunPosition(p, kToWorld);
    const Vec3 back = kToWorld.vector(sunsky::toSphere(local));
    EXPECT_NEAR((back - d).length(), 0.0, 1e-12);
    EXPECT_NO_THROW(makeEmitter(p));

    for (const char *conflict : {"latitude", "longitude", "timezone"}) {
        Properties q = p;
        setFloat(q, conflict, 10.0);
        expectBadParameter(q, "sunDirection");
    }
    Properties q = p;
    q.set("day", Properties::Type::Integer, int64_t(3), kEmitterTestLoc);
    expectBadParameter(q, "sunDirection");
}

TEST(SunSkyParameters, OutOfRange) {
    const std::vector<std::pair<std::string, double>> bad = {
        {"turbidity", 0.5},     {"turbidity", 10.5}, {"stretch", 0.9}, {"stretch", 2.1}, {"latitude", 91},
        {"sunRadiusScale", -1}, {"skyScale", -1},    {"sunScale", -1}, {"scale", -1}};
    for (const auto &[name, value] : bad) {
        Properties p = props(ObjectKind::Emitter, "sunsky");
        setFloat(p, name, value);
        expectBadParameter(p, name);
    }
    for (const std::string plugin : {"sky", "sun"}) {
        Properties p = props(ObjectKind::Emitter, plugin);
        setFloat(p, "scale", 0);
        expectBadParameter(p, "scale");
    }
    Properties p = props(ObjectKind::Emitter, "sky");
    setSpectrum(p, "albedo", Spectrum(0.5, 1.2, 0.5));
    expectBadParameter(p, "albedo");
    p = props(ObjectKind::Emitter, "sky");
    p.set("month", Properties::Type::Integer, int64_t(13), kEmitterTestLoc);
    expectBadParameter(p, "month");
    p = props(ObjectKind::Emitter, "sky");
    p.set("year", Properties::Type::Integer, int64_t(1) << 40, kEmitterTestLoc);
    expectBadParameter(p, "year");
    p = props(ObjectKind::Emitter, "sky");
    p.set("resolution", Properties::Type::Integer, int64_t(1), kEmitterTestLoc);
    expectBadParameter(p, "resolution");
    // Midnight in Tokyo: the sky model has no data for a sun below the horizon.
    p = props(ObjectKind::Emitter, "sky");
    setFloat(p, "hour", 0);
    EXPECT_THROW(makeEmitter(p), SceneError);
}

// sunRadiusScale = 0: the sun becomes a directional emitter of the disk's irradiance, beside the sky.
TEST(SunSkyParameters, DirectionalSun) {
    const auto sun = makeEmitter(sunProperties("sun", kToWorld, 0));
    EXPECT_TRUE(sun->isDelta());
    const Vec3 sunDir = worldSunDirection(kToWorld, 11.5);
    DirectSample ds(Vec3(0.0), Vec3(0.0));
    configured(sun);
    const Spectrum E = sun->sampleDirect(ds, {0.5, 0.5});
    EXPECT_NEAR((ds.d - sunDir).length(), 0.0, 1e-12);
    const auto disk = configured(makeEmitter(sunProperties("sun", kToWorld, 1)));
    EXPECT_NEAR(E.g, disk->power().g / (kPi * 4.0), 1e-9 * E.g);

    const auto sunsky = makeEmitter(sunProperties("sunsky", kToWorld, 0));
    const auto parts = sunsky->companions();
    ASSERT_EQ(parts.size(), 1u);
    EXPECT_TRUE(parts[0]->isDelta());
    EXPECT_FALSE(sunsky->isDelta());
}

// skyScale and sunScale weigh the two parts of sunsky, which are exactly `sky` and `sun` of the same
// parameters; stretch moves the sun to stretch times its zenith angle.
TEST(SunSkyParameters, ScalesAndStretch) {
    const auto make = [](const std::string &plugin, const std::vector<std::pair<std::string, double>> &floats) {
        Properties p = sunProperties(plugin, kToWorld, 1);
        if (plugin == "sky") p.remove("sunRadiusScale");
        p.set("resolution", Properties::Type::Integer, int64_t(64), kEmitterTestLoc);
        for (const auto &[name, value] : floats) setFloat(p, name, value);
        return configured(makeEmitter(p));
    };
    const double sky = make("sky", {})->power().g, sun = make("sun", {})->power().g;
    EXPECT_NEAR(make("sunsky", {})->power().g, sky + sun, 1e-9 * (sky + sun));
    const double scaled = make("sunsky", {{"skyScale", 0.5}, {"sunScale", 2.0}})->power().g;
    EXPECT_NEAR(scaled, 0.5 * sky + 2.0 * sun, 1e-9 * scaled);
    // The map holds floats: a scale other than a power of two rounds differently.
    EXPECT_NEAR(make("sunsky", {{"scale", 3.0}})->power().g, 3.0 * (sky + sun), 1e-6 * sky);
    EXPECT_NEAR(make("sun", {{"scale", 3.0}})->power().g, 3.0 * sun, 1e-9 * sun);

    const auto stretched = make("sun", {{"stretch", 1.5}});
    DirectSample ds(Vec3(0.0), Vec3(0.0));
    stretched->sampleDirect(ds, {0.0, 0.0});  // the disk's centre
    const Vec3 local = normalize(kToWorld.inverse().vector(ds.d));
    sunsky::DateTimeLocation when;
    when.hour = 11.5;
    EXPECT_NEAR(sunsky::fromSphere(local).theta, 1.5 * sunsky::solarPosition(when).theta, 1e-9);
    // Its radiance is that of the unstretched sun.
    EXPECT_NEAR(stretched->power().g, sun, 1e-9 * sun);
}

// ---- rendering ----

// The courtyard of scenes/sunsky at `res` pixels, box filter, with the sun's disk scaled by radiusScale.
std::unique_ptr<Scene> courtyard(int res, const std::string &radiusScale) {
    std::ifstream in(std::string(PATHFARM_SOURCE_DIR) + "/scenes/sunsky/scene.xml");
    std::stringstream xml;
    xml << in.rdbuf();
    std::string s =
        std::regex_replace(xml.str(), std::regex(R"(<rfilter type="[a-z]+"\s*/>)"), R"(<rfilter type="box"/>)");
    s = std::regex_replace(s, std::regex(R"(name="sunRadiusScale" value="[0-9.]+")"),
                           "name=\"sunRadiusScale\" value=\"" + radiusScale + "\"");
    auto scene = loadScene(writeFile(tempDir("sunsky-courtyard-" + radiusScale), "scene.xml", s));
    scene->resizeFilm(res, res);
    return scene;
}

void expectBdptAgreesWithPath(const std::string &radiusScale, size_t emitters) {
    const auto scene = courtyard(16, radiusScale);
    ASSERT_EQ(scene->emitters().size(), emitters);
    ASSERT_NE(scene->environment(), nullptr);
    const auto path = makeTestIntegrator(*scene, "path", {});
    const auto bdpt = makeTestIntegrator(*scene, "bdpt", {});
    const BlockStats ref = blockStats(*scene, *path, 4, 8, 1024, 11);
    const BlockStats test = blockStats(*scene, *bdpt, 4, 8, 512, 12);
    std::printf(
        "sunsky courtyard (sunRadiusScale %s), 16x16, 8 seeds: path %.5f +- %.5f, bdpt %.5f +- %.5f "
        "(whole-image luminance)\n",
        radiusScale.c_str(), ref.mean.back(), ref.stderr_.back(), test.mean.back(), test.stderr_.back());
    expectBlocksAgree(ref, test, 4.0, 0.05, 0.02, "bdpt vs path, sunRadiusScale " + radiusScale);
}

TEST(SunSkyRender, BdptAgreesWithPath) { expectBdptAgreesWithPath("1", 1); }
TEST(SunSkyRender, BdptAgreesWithPathDirectionalSun) { expectBdptAgreesWithPath("0", 2); }

// Every integrator renders the courtyard: a finite image whose mean is that of `path` to within what a
// short render of each can promise.
TEST(SunSkyRender, EveryIntegrator) {
    const auto scene = courtyard(16, "1");
    const auto mean = [&](const std::string &type, int64_t spp) {
        RenderOptions opt;
        opt.spp = spp;
        opt.seed = 5;
        opt.threads = 2;
        RenderStats stats;
        const Bitmap img = makeTestIntegrator(*scene, type, {})->render(*scene, opt, stats);
        for (const float v : img.rgb) EXPECT_TRUE(std::isfinite(v) && v >= 0) << type;
        return regionMean(img, 0, 0, img.width, img.height).mean;
    };
    const double reference = mean("path", 1024);
    std::stringstream names(integratorNames());
    for (std::string name; std::getline(names, name, ',');) {
        name.erase(0, name.find_first_not_of(' '));
        const double m = mean(name, 64);
        std::printf("sunsky courtyard, %s at 64 spp: image mean %.4f (path at 1024 spp: %.4f)\n", name.c_str(), m,
                    reference);
        EXPECT_NEAR(m, reference, 0.1 * reference) << name;
    }
}

}  // namespace
}  // namespace pf::test
