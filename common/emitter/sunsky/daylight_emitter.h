// The environment emitter behind Mitsuba 0.6's `sky`, `sun` and `sunsky`: a sky map (latlong_map.h, the
// Hosek-Wilkie sky rasterized at `resolution`) and a solar disk (sun_disk.h), either or both. As an
// EnvironmentEmitter it serves every integrator, light tracing and BDPT included. Directions are drawn
// from the mixture of the two samplers, picking the sun in proportion to its share of the luminance
// integrated over the sphere, so that it gets the samples the envmap's own importance sampling would give
// a sun splatted into the map (as Mitsuba does); the density is the mixture's, so MIS sees one emitter.
#pragma once
#include <memory>
#include <optional>
#include <vector>

#include "emitter/environment.h"
#include "emitter/latlong_map.h"
#include "emitter/sunsky/sun_disk.h"

namespace pf::sunsky {

class DaylightEmitter final : public EnvironmentEmitter {
public:
    // Reads samplingWeight from props. At least one of sky and sun must be present.
    DaylightEmitter(const Properties &props, const Transform &toWorld, std::optional<LatLongMap> sky,
                    std::optional<SunDisk> sun);

    // Probability that a sampled direction comes from the sun's cone rather than the sky map.
    double sunProbability() const { return sunProbability_; }
    const std::optional<SunDisk> &sun() const { return sun_; }

    std::vector<std::shared_ptr<Emitter>> companions() const override { return companions_; }
    void addCompanion(std::shared_ptr<Emitter> e) { companions_.push_back(std::move(e)); }

protected:
    Spectrum radianceLocal(const Vec3 &v) const override;
    Vec3 sampleLocal(const Vec2 &u, double &pdf) const override;
    double pdfLocal(const Vec3 &v) const override;
    Spectrum integratedRadiance() const override;

private:
    std::optional<LatLongMap> sky_;
    std::optional<SunDisk> sun_;
    double sunProbability_ = 0;
    std::vector<std::shared_ptr<Emitter>> companions_;
};

}  // namespace pf::sunsky
