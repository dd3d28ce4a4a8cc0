// Long statistical checks of `sms` (CTest label "long"): unbiased sms agrees with the path tracer on ring-caustic
// (its light enlarged x15, same radiance, as in test_bdpt), on cornell-box with the tall box made a mirror and
// with that box's caustic flagged out of sms, and on the sphere scene at a larger resolution, also with the
// mirror sphere flagged out of the casters, and with two-vertex chains (bounces = 2); biased sms loses
// energy, less as M grows.
#include <gtest/gtest.h>

#include "support/agreement.h"
#include "support/render_util.h"

namespace pf::test {
namespace {

std::unique_ptr<Integrator> integrator(const Scene &scene, const std::string &type, int64_t trials = 0,
                                       int64_t bounces = 1) {
    Properties props(ObjectKind::Integrator, type, {});
    if (bounces > 1) props.set("bounces", Properties::Type::Integer, bounces, {});
    props.set("maxDepth", Properties::Type::Integer, scene.integratorProperties().getInt("maxDepth", -1), {});
    if (trials > 0) {
        props.set("biased", Properties::Type::Boolean, true, {});
        props.set("trials", Properties::Type::Integer, trials, {});
    }
    return createIntegrator(type, props, true);
}

void expectSmsAgrees(const std::string &scene, const std::vector<Edit> &edits, int res, int pathSpp, int smsSpp,
                     const std::string &what, int64_t bounces = 1) {
    auto s = loadSharedScene(scene, res, edits);
    expectAgreement(blockStats(*s, *integrator(*s, "path"), 8, 32, pathSpp),
                    blockStats(*s, *integrator(*s, "sms", 0, bounces), 8, 32, smsSpp), what);
}

const Edit kBigRingLight{R"(<scale x="0.1" y="0.1" z="0.1"/>)", R"(<scale x="1.5" y="1.5" z="1.5"/>)"};
const Edit kMirrorTallBox{R"(<ref id="TallBox" />)",
                          R"(<bsdf type="conductor"><string name="material" value="none"/></bsdf>)"};

TEST(SmsLong, RingCaustic) { expectSmsAgrees("ring-caustic", {kBigRingLight}, 32, 64, 16, "ring-caustic"); }

TEST(SmsLong, CornellBoxWithAMirrorBox) {
    expectSmsAgrees("cornell-box", {kMirrorTallBox}, 32, 16, 8, "cornell mirror box");
    expectSmsAgrees("cornell-box",
                    {{R"(<ref id="TallBox" />)", R"(<bsdf type="conductor"><string name="material" value="none"/></bsdf>
            <boolean name="causticCaster" value="false"/>)"}},
                    32, 16, 8, "cornell mirror box, not a caster");
}

// The light enlarged x4 (radiance / 16).
const std::vector<Edit> kBigSphereLight = {
    {R"(<scale x="0.15" y="0.15" z="0.15"/>)", R"(<scale x="0.6" y="0.6" z="0.6"/>)"},
    {R"(value="3000")", R"(value="190")"}};

// With and without the mirror sphere among the casters.
TEST(SmsLong, SphereCaustic) {
    expectSmsAgrees("sphere-caustic", kBigSphereLight, 32, 128, 32, "sphere-caustic");
    std::vector<Edit> notCaster = kBigSphereLight;
    notCaster.push_back({R"(<float name="radius" value="0.8"/>)",
                         R"(<float name="radius" value="0.8"/><boolean name="causticCaster" value="false"/>)"});
    expectSmsAgrees("sphere-caustic", notCaster, 32, 128, 32, "sphere-caustic, mirror sphere not a caster");
}

// Two-refraction chains through the glass sphere estimated by sms (bounces = 2). The path tracer finds the far
// floor's share of the glass caustic only in rare paths: at 128 spp its block means there are low, with too small
// standard errors (seen at 32²: a corner block 0.10533 at 128 spp, 0.10598 +- 0.00028 at 512 spp, sms 0.10592).

TEST(SmsLong, SphereCausticTwoBounces) {
    expectSmsAgrees("sphere-caustic", kBigSphereLight, 32, 512, 128, "sphere-caustic, bounces=2", 2);
}

// Biased sms: the image's mean is below unbiased sms's and rises with M (the energy loss of [SMS §5.2]).
TEST(SmsLong, BiasedLosesEnergyLessAsMGrows) {
    auto s = loadSharedScene("ring-caustic", 32, {kBigRingLight});
    const BlockStats unbiased = blockStats(*s, *integrator(*s, "sms"), 32, 16, 16);
    double previous = 0, previousErr = 0;
    for (int64_t m : {1, 4, 16}) {
        const BlockStats b = blockStats(*s, *integrator(*s, "sms", m), 32, 16, 16);
        const double mean = b.mean.back(), err = b.stderr_.back();
        EXPECT_LE(mean, unbiased.mean.back() + 4 * std::hypot(err, unbiased.stderr_.back())) << "M = " << m;
        EXPECT_GE(mean, previous - 4 * std::hypot(err, previousErr)) << "M = " << m;
        previous = mean;
        previousErr = err;
    }
}

}  // namespace
}  // namespace pf::test
