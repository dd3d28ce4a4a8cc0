// Mitsuba 0.6 "isotropic": scattering into every direction with the same density 1 / (4 pi), sampled
// exactly (so sample() always returns weight 1).
#include "core/warp.h"
#include "medium/media.h"

namespace pf {

namespace {

class IsotropicPhase final : public PhaseFunction {
public:
    double eval(const Vec3 &, const Vec3 &) const override { return kInvFourPi; }
    double pdf(const Vec3 &, const Vec3 &) const override { return kInvFourPi; }
    double sample(const Vec3 &, Vec3 &wo, double &pdf, const Vec2 &u) const override {
        wo = warp::squareToUniformSphere(u);
        pdf = kInvFourPi;
        return 1.0;
    }
    double meanCosine() const override { return 0.0; }
};

}  // namespace

std::shared_ptr<PhaseFunction> makeIsotropicPhase() { return std::make_shared<IsotropicPhase>(); }

std::shared_ptr<Object> createIsotropicPhase(const Properties &, const LoadContext &) { return makeIsotropicPhase(); }

}  // namespace pf
