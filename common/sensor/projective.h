// Perspective projection shared by Mitsuba 0.6's "perspective" (pinhole) and "thinlens" sensors.
//
// Camera space: the camera sits at the origin looking along +z with +y up; raster x grows towards local
// -x (Mitsuba's handedness: with a lookat transform, what lies to the camera's left appears on the image's
// left). On the plane z = 1 the full film spans [-tx, tx] x [-ty, ty] with tx = tan(xfov / 2) and
// ty = tx * height / width; the crop window is the part of it that is rendered, and raster (0, 0) is the
// crop window's corner.
//
// Importance. Let A be the area of the crop window on the plane z = 1. Choosing the raster position
// uniformly and shooting through it gives, from any aperture point, the solid-angle density
// 1 / (A cos^3 theta) (Mitsuba's derivation: the image point is uniform on a rectangle of area A f^2 at the
// focus distance f, at distance f / cos theta and seen at angle theta). pathfarm's convention, like
// Mitsuba's, is that evalDirection returns We * cos theta, the importance times the cosine at the
// aperture, and makes it equal to that density:
//
//     evalDirection = pdfDirection = 1 / (A cos^3 theta),  i.e.  We = 1 / (A cos^4 theta)  (pbrt-v3 §16.1.1),
//
// so the integral of evalDirection over the directions that reach the image is 1, and the pixel a path
// contributes to is read from its raster position. evalPosition is 1 for the pinhole (a Discrete
// position) and 1 / (pi r^2) on a thin lens of radius r (the uniform aperture density), so
// evalPosition * evalDirection = We * cos theta. sampleDirect returns
// evalPosition * evalDirection / (dist^2 * aperture density), the importance arriving at the reference
// point per unit solid-angle density (no cosine at the reference point; the integrator applies it, as
// with emitters).
#pragma once
#include "scene/plugins.h"
#include "sensor/sensor.h"

namespace pf {

class ProjectiveCamera : public Sensor {
public:
    // Reads toWorld, fov / fovAxis or focalLength, nearClip, farClip and the nested film and sampler.
    // A pinhole until setThinLens is called.
    ProjectiveCamera(const Properties &props, const LoadContext &ctx);

    Spectrum sampleRay(Ray &ray, const Vec2 &raster, const Vec2 &aperture) const override;
    Spectrum samplePosition(PositionSample &ps, const Vec2 &u) const override;
    Spectrum evalPosition(const PositionSample &ps) const override;
    double pdfPosition(const PositionSample &ps) const override;
    Spectrum sampleDirection(DirectionSample &ds, PositionSample &ps, const Vec2 &raster) const override;
    Spectrum evalDirection(const DirectionSample &ds, const PositionSample &ps) const override;
    double pdfDirection(const DirectionSample &ds, const PositionSample &ps) const override;
    Spectrum evalDirectionAndPdf(const DirectionSample &ds, const PositionSample &ps, double &pdf) const override;
    Spectrum sampleDirect(DirectSample &ds, const Vec2 &u) const override;
    double pdfDirect(const DirectSample &ds) const override;
    bool rasterPosition(const Vec3 &p, const Vec3 &d, Vec2 &raster) const override;
    bool deltaAperture() const override { return apertureRadius_ == 0; }
    bool intersectAperture(const Ray &ray, PositionSample &ps, double &t) const override;
    // Recomputes the raster mapping from the film (its size may have changed since construction).
    void configure(const Scene &scene) override;

    // Horizontal field of view in degrees after applying fovAxis / focalLength to the film's aspect.
    double xFov() const { return xFovDeg_; }

protected:
    // Thin lens of the given aperture radius focused at distance focusDistance along the view axis.
    void setThinLens(double apertureRadius, double focusDistance);

private:
    enum class FovAxis { X, Y, Diagonal, Smaller, Larger };
    void updateProjection();
    // Camera-space aperture point for a uniform sample (the origin for a pinhole).
    Vec3 aperturePoint(const Vec2 &u) const;
    Vec3 toLocalPoint(const Vec3 &p) const;
    // Point on the plane z = 1 seen through crop raster position `raster`.
    Vec3 rasterToPlane(const Vec2 &raster) const;
    // We * cos theta for the camera-space ray (a, d), d unit; zero unless it reaches the crop window.
    // Also returns the raster position.
    double importance(const Vec3 &a, const Vec3 &d, Vec2 &raster) const;
    double aperturePdf() const { return aperturePdf_; }

    double fov_ = 0;  // degrees, along fovAxis_
    FovAxis fovAxis_ = FovAxis::X;
    double xFovDeg_ = 0, tanX_ = 0, tanY_ = 0, invImageArea_ = 0;
    double apertureRadius_ = 0, focusDistance_ = 1;
    // Derived in updateProjection: rasterToPlane's and importance's affine maps, and the aperture's density.
    Vec2 planeScale_, planeOrigin_, rasterScale_, rasterOrigin_;
    double aperturePdf_ = 0;
    Transform worldToLocal_;
};

}  // namespace pf
