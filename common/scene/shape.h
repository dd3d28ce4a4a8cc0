// Shapes: triangle meshes (obj, ply, serialized, rectangle, cube) and analytic surfaces (sphere,
// cylinder, disk). Triangle meshes go to Embree as triangle geometry; analytic shapes as Embree user
// geometry whose callbacks intersect in double precision.
#pragma once
#include <embree3/rtcore.h>

#include <memory>
#include <optional>

#include "core/vector.h"
#include "scene/intersection.h"
#include "scene/object.h"
#include "scene/records.h"

namespace pf {

class BSDF;
class Emitter;
class Medium;
class Properties;

class Shape : public Object {
public:
    // Adds this shape's geometry to an Embree scene and returns the geometry id.
    virtual unsigned addToEmbree(RTCDevice device, RTCScene scene) const = 0;
    // Completes `its` from an Embree hit: `primIndex`, Embree's (u, v) and the ray distance t.
    // Analytic shapes re-intersect in double precision here.
    virtual void fillIntersection(const Ray &ray, double t, uint32_t primIndex, const Vec2 &embreeUV,
                                  Intersection &its) const = 0;
    // Computes dn/du and dn/dv of a hit that fillIntersection left with normalDerivativesPending (meshes).
    virtual void fillNormalDerivatives(Intersection &) const {}
    virtual AABB bbox() const = 0;
    virtual double surfaceArea() const = 0;
    virtual size_t primitiveCount() const = 0;

    // Uniform position sampling by area (pdf = 1 / surfaceArea, Measure::Area).
    virtual void samplePosition(PositionSample &ps, const Vec2 &u) const = 0;
    virtual double pdfPosition(const PositionSample &) const { return 1.0 / surfaceArea(); }
    // Direct sampling from ds.ref: fills p, n, uv, d, dist and pdf in solid angle at ref.
    // Default: area sampling converted to solid angle. Spheres override with cone sampling.
    virtual void sampleDirect(DirectSample &ds, const Vec2 &u) const;
    virtual double pdfDirect(const DirectSample &ds) const;

    const BSDF *bsdf() const { return bsdf_.get(); }
    const Emitter *emitter() const { return emitter_.get(); }
    const Medium *interiorMedium() const { return interior_.get(); }
    const Medium *exteriorMedium() const { return exterior_.get(); }
    const std::shared_ptr<BSDF> &bsdfPtr() const { return bsdf_; }
    const std::shared_ptr<Emitter> &emitterPtr() const { return emitter_; }

    // Specular manifold sampling's roles (ALGORITHMS.md §7.1; XML booleans causticCaster / causticReceiver,
    // which Mitsuba 0.6 does not have): nullopt when the scene leaves them to the defaults of manifold/sms.h.
    std::optional<bool> causticCaster() const { return causticCaster_; }
    std::optional<bool> causticReceiver() const { return causticReceiver_; }

    void setBSDF(std::shared_ptr<BSDF> b) { bsdf_ = std::move(b); }
    void setEmitter(std::shared_ptr<Emitter> e) { emitter_ = std::move(e); }
    void setMedia(std::shared_ptr<Medium> interior, std::shared_ptr<Medium> exterior) {
        interior_ = std::move(interior);
        exterior_ = std::move(exterior);
    }

protected:
    // Reads the children shared by every shape (bsdf, emitter, interior/exterior medium refs) from the
    // plugin's properties; the default BSDF is a diffuse one with reflectance 0.5 (Mitsuba).
    void configureCommon(const Properties &props);

private:
    std::shared_ptr<BSDF> bsdf_;
    std::shared_ptr<Emitter> emitter_;
    std::shared_ptr<Medium> interior_, exterior_;
    std::optional<bool> causticCaster_, causticReceiver_;
};

inline const BSDF *Intersection::bsdf() const { return shape ? shape->bsdf() : nullptr; }

}  // namespace pf
