// Separable reconstruction filters (Mitsuba's rfilter: box, tent, gaussian, mitchell, catmullrom, lanczos).
#pragma once
#include <vector>

#include "scene/object.h"

namespace pf {

// Largest filter radius (in pixels) an ImageBlock accepts: it bounds the per-sample footprint and the
// tile border, so a scene asking for an absurd filter fails at load time instead of stalling a render.
constexpr double kMaxFilterRadius = 16.0;

class ReconstructionFilter : public Object {
public:
    // Filter radius in pixels (box 0.5, tent 1, gaussian 4*stddev with stddev 0.5).
    double radius() const { return radius_; }
    // 1D filter value at offset x (|x| <= radius); the 2D filter is eval(x) * eval(y).
    virtual double eval(double x) const = 0;
    // Pixels an ImageBlock keeps beyond its region so that every sample inside the region reaches all
    // the pixels its filter touches (Mitsuba's getBorderSize: ceil(radius - 0.5)).
    int borderSize() const;

protected:
    double radius_ = 0.5;
};

// The filters of Mitsuba 0.6 (src/rfilters). Parameters are validated by the plugin factories in
// image/film_plugins.cpp; the constructors assume valid values.
class BoxFilter final : public ReconstructionFilter {
public:
    explicit BoxFilter(double radius = 0.5);
    double eval(double x) const override;
};

class TentFilter final : public ReconstructionFilter {
public:
    TentFilter();  // radius 1, as Mitsuba's tent (not configurable there either)
    double eval(double x) const override;
};

class GaussianFilter final : public ReconstructionFilter {
public:
    explicit GaussianFilter(double stddev = 0.5);
    double eval(double x) const override;
    double stddev() const { return stddev_; }

private:
    double stddev_, alpha_, bias_;
};

// Mitchell-Netravali cubic (B, C); catmullrom is the special case B = 0, C = 1/2. Radius 2.
class MitchellNetravaliFilter final : public ReconstructionFilter {
public:
    MitchellNetravaliFilter(double B = 1.0 / 3.0, double C = 1.0 / 3.0);
    double eval(double x) const override;

private:
    double B_, C_;
};

class LanczosSincFilter final : public ReconstructionFilter {
public:
    explicit LanczosSincFilter(int lobes = 3);  // radius = lobes
    double eval(double x) const override;
};

}  // namespace pf
