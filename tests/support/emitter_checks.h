// Checks shared by the emitter tests (test_emitters, test_sunsky): building emitters from properties,
// chi-square tests of their direction densities (light tracing and next-event estimation), the power
// that light tracing estimates, and the agreement of direct sampling with the position x direction split
// that BDPT evaluates.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "emitter/emitter.h"
#include "scene/plugins.h"
#include "support/chi2.h"

namespace pf::test {

inline const SourceLocation kEmitterTestLoc{"test.xml", 1};

Chi2Options emitterChi2Options(int testCount, int thetaBins = 10, int phiBins = 20, int integrationRes = 6);

Properties props(ObjectKind kind, const std::string &plugin);
void setFloat(Properties &p, const std::string &name, double v);
void setSpectrum(Properties &p, const std::string &name, const Spectrum &v);
void setTransform(Properties &p, const std::string &name, const Transform &t);

// Runs the plugin's factory and checks that every parameter was used.
std::shared_ptr<Emitter> makeEmitter(const Properties &p, const LoadContext &ctx = {});
// The factory fails with a message naming `param`.
void expectBadParameter(const Properties &p, const std::string &param, const LoadContext &ctx = {});

// Chi-square of the emission directions sampleDirection draws at a sampled position against pdfDirection.
Chi2Result emissionChi2(const Emitter &e, const PositionSample &ps, const Chi2Options &opt);
// Chi-square of the directions sampleDirect produces from ref against pdfDirect, where `hit` completes the
// record for a direction (false where the emitter is not in that direction).
Chi2Result directChi2(const Emitter &e, const Vec3 &ref,
                      const std::function<bool(const Vec3 &, const Vec3 &, DirectSample &)> &hit,
                      const Chi2Options &opt);
// Mean and standard error of the light-tracing weight samplePosition * sampleDirection (luminance), whose
// expectation is the emitted power.
void expectLightTracingPower(const Emitter &e, int n = 200000);
// Direct sampling agrees with the position / direction split: for non-delta emitters the arriving
// radiance value * pdf equals evalPosition * evalDirection / cos at the emitter, for delta positions
// value = evalPosition * evalDirection / dist^2; and pdfDirect reproduces ds.pdf.
void expectDirectMatchesSplit(const Emitter &e, const std::vector<Vec3> &refs);
// A hit on the bounding sphere, as an environment vertex (the sphere's far side from o).
bool environmentHit(const Emitter &e, const Vec3 &o, const Vec3 &d, DirectSample &ds);

}  // namespace pf::test
