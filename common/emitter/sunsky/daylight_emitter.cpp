#include "emitter/sunsky/daylight_emitter.h"

namespace pf::sunsky {

DaylightEmitter::DaylightEmitter(const Properties &props, const Transform &toWorld, std::optional<LatLongMap> sky,
                                 std::optional<SunDisk> sun)
    : EnvironmentEmitter(toWorld), sky_(std::move(sky)), sun_(std::move(sun)) {
    configureCommon(props);
    if (!sky_) {
        sunProbability_ = 1.0;
    } else if (sun_) {
        const double sunPower = sun_->integral().luminance(), skyPower = sky_->integral().luminance();
        sunProbability_ = sunPower > 0 ? sunPower / (sunPower + skyPower) : 0.0;
    }
}

Spectrum DaylightEmitter::radianceLocal(const Vec3 &v) const {
    Spectrum L(0.0);
    if (sky_) L += sky_->eval(v);
    if (sun_) L += sun_->eval(v);
    return L;
}

// One uniform number picks the component and is stretched back to [0, 1) for it.
Vec3 DaylightEmitter::sampleLocal(const Vec2 &u, double &pdf) const {
    double componentPdf = 0;
    Vec3 v;
    if (u.x < sunProbability_) {
        v = sun_->sample({u.x / sunProbability_, u.y}, componentPdf);
    } else {
        v = sky_->sample({(u.x - sunProbability_) / (1.0 - sunProbability_), u.y}, componentPdf);
    }
    pdf = componentPdf > 0 ? pdfLocal(v) : 0.0;
    return v;
}

double DaylightEmitter::pdfLocal(const Vec3 &v) const {
    double pdf = 0;
    if (sun_ && sunProbability_ > 0) pdf += sunProbability_ * sun_->pdf(v);
    if (sky_ && sunProbability_ < 1) pdf += (1.0 - sunProbability_) * sky_->pdf(v);
    return pdf;
}

Spectrum DaylightEmitter::integratedRadiance() const {
    Spectrum sum(0.0);
    if (sky_) sum += sky_->integral();
    if (sun_) sum += sun_->integral();
    return sum;
}

}  // namespace pf::sunsky
