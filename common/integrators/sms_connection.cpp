#include "integrators/sms_connection.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <vector>

#include "bsdf/bsdf.h"
#include "core/error.h"
#include "emitter/emitter.h"
#include "scene/scene.h"
#include "scene/shape.h"

namespace pf {

namespace {

bool isCaster(const Shape &shape) {
    return specularEvent(shape) != Scattering::None && shape.causticCaster().value_or(true);
}

// Emitters SMS can connect to: those with a position to solve towards.
bool hasPosition(const Emitter &emitter) {
    return !emitter.isEnvironment() && !(emitter.flags() & EmitterFlags::DeltaDirection);
}

// The emitter vertex x_3 of the chain: a point light is a fixed position; an area light's point is an
// unconstrained endpoint whose chart never enters G(x_1 -> x_2 -> x_3) beyond its normal.
ManifoldVertex emitterVertex(const PositionSample &ps) {
    if (ps.measure == Measure::Discrete) return ManifoldVertex::fixedPosition(ps.p);
    ManifoldVertex v;
    v.p = ps.p;
    v.ng = v.n = ps.n;
    coordinateSystem(ps.n, v.dpdu, v.dpdv);
    return v;
}

}  // namespace

SmsConnection::SmsConnection(const Properties &props) {
    settings_.biased = props.getBool("biased", false);
    settings_.trials = props.getInt("trials", settings_.biased ? 8 : settings_.trials);
    const std::string constraint = props.getString("constraint", "angle");
    if (constraint == "angle")
        settings_.constraint = SmsConstraint::AngleDifference;
    else if (constraint == "halfvector")
        settings_.constraint = SmsConstraint::HalfVector;
    else
        props.fail("constraint", "must be 'angle' or 'halfvector'");
    settings_.maxIterations = static_cast<int>(props.getInt("maxIterations", settings_.maxIterations));
    settings_.solverThreshold = props.getFloat("solverThreshold", settings_.solverThreshold);
    settings_.uniquenessThreshold = props.getFloat("uniquenessThreshold", settings_.uniquenessThreshold);
    bounces_ = static_cast<int>(props.getInt("bounces", 1));
    if (settings_.trials < 1) props.fail("trials", "must be at least 1");
    if (settings_.maxIterations < 1) props.fail("maxIterations", "must be at least 1");
    if (!(settings_.solverThreshold > 0)) props.fail("solverThreshold", "must be positive");
    if (!(settings_.uniquenessThreshold > 0)) props.fail("uniquenessThreshold", "must be positive");
    if (bounces_ != 1 && bounces_ != 2) props.fail("bounces", "must be 1 or 2 (the longest specular chain)");
}

void SmsConnection::check(const Scene &scene) const {
    for (const auto &shape : scene.shapes())
        if (shape->causticCaster().value_or(false) && specularEvent(*shape) == Scattering::None)
            throw SceneError(shape->location(),
                             "causticCaster: the shape's BSDF is not ideally specular (conductor or dielectric)");
    for (const auto &emitter : scene.emitters())
        if (emitter->causticEmitter().value_or(false) && !hasPosition(*emitter))
            throw SceneError(emitter->location(), "causticEmitter: sms connects only to area, point and spot emitters");
}

void SmsConnection::begin() const { stats_.reset(); }

void SmsConnection::end() const {
    std::fprintf(stderr, "sms: %" PRIu64 " estimates, %" PRIu64 " solver trials, success rate %.1f%%",
                 stats_.estimates.load(), stats_.solves.load(), 100.0 * stats_.successRate());
    if (!settings_.biased)
        std::fprintf(stderr, ", trials per solution: mean %.2f, max %" PRIu64 ", runaway guard hits %" PRIu64,
                     stats_.meanTrials(), stats_.maxTrials.load(), stats_.guardHits.load());
    std::fprintf(stderr, "\n");
}

bool SmsConnection::receives(const Intersection &its) const {
    return its.shape->causticReceiver().value_or(!isCaster(*its.shape));
}

bool SmsConnection::casts(const Intersection &its, uint32_t sampledLobe) const {
    if (!isCaster(*its.shape)) return false;
    const Scattering event = specularEvent(*its.shape);
    return sampledLobe == (event == Scattering::Refraction ? BSDFFlags::DeltaTransmission : BSDFFlags::DeltaReflection);
}

bool SmsConnection::connectsTo(const Emitter &emitter) const {
    return hasPosition(emitter) && emitter.causticEmitter().value_or(true);
}

Spectrum SmsConnection::estimate(const Scene &scene, Sampler &sampler, const Intersection &x1, int budget) const {
    std::vector<const Emitter *> emitters;
    for (const auto &e : scene.emitters())
        if (connectsTo(*e)) emitters.push_back(e.get());
    if (emitters.empty()) return {};
    const double pick = sampler.next1D() * static_cast<double>(emitters.size());
    const Emitter &emitter = *emitters[std::min(emitters.size() - 1, static_cast<size_t>(pick))];
    PositionSample ps;
    emitter.samplePosition(ps, sampler.next2D());
    if (!(ps.pdf > 0)) return {};
    const double invPdf = static_cast<double>(emitters.size()) / ps.pdf;
    const Spectrum emission = emitter.evalPosition(ps);
    const ManifoldVertex x3 = emitterVertex(ps);
    const BSDF &receiverBsdf = *x1.bsdf();

    // f(x_1) F(x_2) … G L_e / p(x_3) of one solved chain, visibility of its last vertex and x_3 included (the
    // chain's own segments are the solver's first hits). A chain whose later vertex is not a caster is the path
    // tracer's (caustic_connection.h): it contributes nothing here.
    const auto contribution = [&](const SpecularChain &chain) -> Spectrum {
        const Intersection &last = chain.back();
        const Vec3 d12 = normalize(chain.front().p - x1.p), d32 = normalize(last.p - ps.p);
        const Spectrum f1 = receiverBsdf.eval(BSDFContext(), x1, x1.wi, x1.toLocal(d12));
        DirectionSample out;
        out.d = d32;
        Spectrum le = emission * emitter.evalDirection(out, ps);
        if (f1.isBlack() || le.isBlack()) return {};
        // evalPosition * evalDirection is L_e cos at an area light (emitter.h); G has that cosine already.
        if (ps.measure != Measure::Discrete) le *= 1.0 / std::abs(dot(ps.n, d32));
        Spectrum specular(1.0);
        for (const Intersection &x2 : chain) {
            if (!isCaster(*x2.shape)) return {};
            BSDFSample bs;
            const Scattering event = specularEvent(*x2.shape);
            const BSDFContext lobe(TransportMode::Radiance, event == Scattering::Refraction
                                                                ? BSDFFlags::DeltaTransmission
                                                                : BSDFFlags::DeltaReflection);
            specular *= x2.bsdf()->sample(lobe, x2, x2.wi, bs, 0.5, Vec2(0.5, 0.5));
        }
        if (specular.isBlack() || scene.occluded(scene.spawnRayTo(last, ps.p))) return {};
        const std::optional<double> g = specularChainGeometry(x1, chain, x3);
        return g ? f1 * specular * le * (*g * invPdf) : Spectrum();
    };

    Spectrum sum;
    for (const auto &shape : scene.shapes())
        if (isCaster(*shape))
            for (int vertices = 1; vertices <= std::min(budget, bounces_); ++vertices)
                sum += manifoldSum(scene, x1, ps.p, *shape, vertices, settings_, sampler, stats_, contribution);
    return sum;
}

}  // namespace pf
