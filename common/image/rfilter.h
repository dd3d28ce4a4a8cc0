// Separable reconstruction filters (Mitsuba's rfilter: box, tent, gaussian), tabulated.
#pragma once
#include <vector>

#include "scene/object.h"

namespace pf {

class ReconstructionFilter : public Object {
public:
    // Filter radius in pixels (box 0.5, tent 1, gaussian 4*stddev with stddev 0.5).
    double radius() const { return radius_; }
    // 1D filter value at offset x (|x| <= radius); the 2D filter is eval(x) * eval(y).
    virtual double eval(double x) const = 0;

protected:
    double radius_ = 0.5;
};

}  // namespace pf
