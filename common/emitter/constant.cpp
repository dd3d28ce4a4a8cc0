// Mitsuba 0.6's "constant" environment emitter: the same radiance from every direction. Directions are
// sampled uniformly on the sphere, which is proportional to the radiance.
#include "core/warp.h"
#include "emitter/endpoint.h"
#include "emitter/environment.h"
#include "scene/plugins.h"

namespace pf {

namespace {

class ConstantEmitter final : public EnvironmentEmitter {
public:
    explicit ConstantEmitter(const Properties &props)
        : EnvironmentEmitter(Transform()), radiance_(nonNegativeSpectrum(props, "radiance", Spectrum(1.0))) {
        configureCommon(props);
    }

protected:
    Spectrum radianceLocal(const Vec3 &) const override { return radiance_; }
    Vec3 sampleLocal(const Vec2 &u, double &pdf) const override {
        pdf = warp::squareToUniformSpherePdf();
        return warp::squareToUniformSphere(u);
    }
    double pdfLocal(const Vec3 &) const override { return warp::squareToUniformSpherePdf(); }
    Spectrum integratedRadiance() const override { return radiance_ * (4.0 * kPi); }

private:
    Spectrum radiance_;
};

}  // namespace

std::shared_ptr<Object> createConstantEmitter(const Properties &props, const LoadContext &) {
    return std::make_shared<ConstantEmitter>(props);
}

}  // namespace pf
