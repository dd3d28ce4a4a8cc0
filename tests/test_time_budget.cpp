// Every integrator under a wall-time budget (`render --time`) converges to the image it converges to under a
// sample budget: block means of independent timed renders against a BDPT reference rendered with `--spp`.
// A timed render stops between whole passes (image integrators) or whole chain tasks (Markov chains); a
// stopping rule that looks at what a pass found (e.g. ending early after a dark pass, or weighting passes by
// their length) biases the image, and the comparison catches it at the thresholds of timeBudgetSetup: renders
// on a loaded machine are short, so the noise guards are those at which a 15% bias still stands out at 4.5
// standard errors. ERPT, MEPT, SMS and two-stage MLT have their own timed cases beside their sample-budget
// ones (test_erpt, test_mept, test_sms, test_two_stage); these are the rest.
#include <gtest/gtest.h>

#include "test_mlt_common.h"

namespace pf::test {
namespace {

struct Case {
    // Names the case in gtest output instead of dumping its bytes.
    friend void PrintTo(const Case &c, std::ostream *os) { *os << c.scene << " " << c.integrator; }
    std::string scene, integrator;
    std::vector<std::pair<std::string, std::string>> params;
    double seconds = 0.3;
    int referenceSpp = 64;
};

class TimeBudget : public ::testing::TestWithParam<Case> {};

TEST_P(TimeBudget, AgreesWithBDPTAtASampleBudget) {
    const Case &c = GetParam();
    ConvergenceSetup s = timeBudgetSetup(c.seconds);
    s.referenceSpp = c.referenceSpp;
    expectConvergence(c.scene, c.integrator, c.params, s,
                      testing::PrintToString(c) + " --time " + testing::PrintToString(c.seconds));
}

// cornell-box's file asks for `sobol` (pixel samples stratified in every request, core/ld_sampler.h); its copies
// with `independent`, with `ldsampler` of dimension 3 (later requests independent) and with `sobol` of layout
// "image" (one sequence through the image, core/global_sobol_sampler.h) are rendered too.
// The Markov chains leave every path to the chains (directSamples = -1), so the stopping rule is all that
// decides how much of the image each timed render holds. volpath renders the egg filled with a medium under
// the larger light (test_mlt_common.h's variant): volpath reaches a light behind glass only by hitting it, and
// volumetric-caustic's 5 x 4 mm light is hit so rarely that 2048 samples per pixel still come out 20-35% dark
// in its caustic (bench_per_sample --res 16 --spp 2048 --integrators volpath: the heavy tail, not a bias).
const std::vector<std::pair<std::string, std::string>> kChainsOnly = {{"directSamples", "-1"},
                                                                      {"luminanceSamples", "2048"}};
INSTANTIATE_TEST_SUITE_P(
    Integrators, TimeBudget,
    ::testing::Values(Case{"cornell-box", "path", {}}, Case{"cornell-box", "bdpt", {}},
                      Case{"cornell-box-independent", "path", {}}, Case{"cornell-box-ldsampler", "bdpt", {}},
                      Case{"cornell-box-imagesobol", "path", {}}, Case{"cornell-box-imagesobol", "bdpt", {}},
                      Case{"glass-egg-largelight", "volpath", {}, 0.5, 512}, Case{"cornell-box", "pssmlt", kChainsOnly},
                      Case{"cornell-box", "mmlt", kChainsOnly}, Case{"cornell-box", "mlt", kChainsOnly},
                      Case{"veach-bidir", "memlt", kChainsOnly}),
    [](const auto &info) { return gtestName(info.param.scene + "_" + info.param.integrator); });

}  // namespace
}  // namespace pf::test
