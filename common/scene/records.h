// Sampling records shared by shapes, emitters and sensors (Mitsuba's PositionSamplingRecord,
// DirectionSamplingRecord and DirectSamplingRecord). These carry everything the bidirectional methods
// need: positions with their normals and area densities, directions with solid-angle densities, and the
// measure each density is expressed in (delta endpoints use Discrete).
#pragma once
#include "core/vector.h"

namespace pf {

class Object;
class Shape;

enum class Measure { Area, SolidAngle, Discrete, Length };

struct PositionSample {
    Vec3 p;
    Vec3 n;          // surface normal at p (zero for a point with no surface)
    Vec2 uv;         // surface parameterization (sensors: raster position after sampleDirection)
    double pdf = 0;  // area density, or 1 for Measure::Discrete
    Measure measure = Measure::Area;
    const Shape *shape = nullptr;  // shape the position lies on (area emitters)
};

struct DirectionSample {
    Vec3 d;          // world-space unit direction
    double pdf = 0;  // solid-angle density, or 1 for Measure::Discrete
    Measure measure = Measure::SolidAngle;
};

// Direct sampling of an endpoint (emitter or sensor) from a reference point `ref`.
struct DirectSample {
    Vec3 ref;         // reference point (in: set by caller)
    Vec3 refN;        // its normal, or zero inside media (in; may be used to cull)
    Vec3 p;           // sampled point on the endpoint (out)
    Vec3 n;           // normal there (out; zero for points and environment)
    Vec2 uv;          // surface coordinates, or raster position for sensors (out)
    Vec3 d;           // unit direction from ref to p (out)
    double dist = 0;  // distance from ref to p (infinite for environment emitters)
    double pdf = 0;   // solid-angle density at ref, or 1 for Measure::Discrete
    Measure measure = Measure::SolidAngle;
    const Object *object = nullptr;  // the emitter or sensor that was sampled
    DirectSample() = default;
    DirectSample(const Vec3 &ref_, const Vec3 &refN_) : ref(ref_), refN(refN_) {}
};

}  // namespace pf
