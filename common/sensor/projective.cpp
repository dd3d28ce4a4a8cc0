#include "sensor/projective.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "core/warp.h"
#include "emitter/endpoint.h"
#include "image/film.h"
#include "scene/medium.h"
#include "scene/sampler_settings.h"

namespace pf {

namespace {

std::shared_ptr<Film> nestedFilm(const Properties &props, const LoadContext &ctx) {
    const auto films = props.children(ObjectKind::Film);
    if (films.size() > 1) props.fail("a sensor takes at most one film");
    std::shared_ptr<Object> object;
    if (films.empty()) {
        // Mitsuba's default: an hdrfilm with its own defaults (768 x 576, gaussian filter).
        const PluginFactory *factory = findPlugin(ObjectKind::Film, "hdrfilm");
        if (!factory) props.fail("no 'hdrfilm' plugin is available for the default film");
        object = (*factory)(Properties(ObjectKind::Film, "hdrfilm", props.location()), ctx);
    } else {
        object = films.front();
    }
    auto film = std::dynamic_pointer_cast<Film>(object);
    if (!film) props.fail("the nested film is not a film");
    return film;
}

// Mitsuba's default sampler is `independent` with 4 samples per pixel.
SamplerSettings nestedSampler(const Properties &props) {
    const auto samplers = props.children(ObjectKind::Sampler);
    if (samplers.size() > 1) props.fail("a sensor takes at most one sampler");
    if (samplers.empty()) return SamplerSettings(4, {});
    const auto settings = std::dynamic_pointer_cast<SamplerSettings>(samplers.front());
    if (!settings) props.fail("the nested sampler is not a sampler");
    return *settings;
}

// Mitsuba's focalLength: a 35 mm film equivalent "<x>mm" (or a bare number), turned into the diagonal
// field of view of a 36 x 24 mm frame.
double focalLengthToDiagonalFov(const Properties &props) {
    std::string text = props.getString("focalLength", "50mm");
    if (text.size() > 2 && text.compare(text.size() - 2, 2, "mm") == 0) text.resize(text.size() - 2);
    char *end = nullptr;
    const double mm = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !std::isfinite(mm) || !(mm > 0))
        props.fail("focalLength", "must have the form <x>mm with a positive number x");
    return radToDeg(2.0 * std::atan(std::sqrt(36.0 * 36.0 + 24.0 * 24.0) / (2.0 * mm)));
}

}  // namespace

ProjectiveCamera::ProjectiveCamera(const Properties &props, const LoadContext &ctx) {
    setToWorld(rigidTransform(props, "toWorld"));
    worldToLocal_ = toWorld().inverse();

    // A camera inside a participating medium (Mitsuba: an unnamed medium child or ref of <sensor>).
    const auto media = props.children(ObjectKind::Medium);
    if (media.size() > 1) props.fail("a sensor sits in at most one medium");
    if (!media.empty()) {
        medium_ = std::dynamic_pointer_cast<Medium>(media.front());
        if (!medium_) props.fail("the nested medium is not a medium");
    }

    nearClip_ = props.getFloat("nearClip", 1e-2);
    farClip_ = props.getFloat("farClip", 1e4);
    if (!(nearClip_ > 0)) props.fail("nearClip", "must be positive");
    if (!(farClip_ > nearClip_)) props.fail("farClip", "must be greater than nearClip");

    std::string axis = props.getString("fovAxis", "x");
    std::transform(axis.begin(), axis.end(), axis.begin(), [](unsigned char c) { return std::tolower(c); });
    if (axis == "x")
        fovAxis_ = FovAxis::X;
    else if (axis == "y")
        fovAxis_ = FovAxis::Y;
    else if (axis == "diagonal")
        fovAxis_ = FovAxis::Diagonal;
    else if (axis == "smaller")
        fovAxis_ = FovAxis::Smaller;
    else if (axis == "larger")
        fovAxis_ = FovAxis::Larger;
    else
        props.fail("fovAxis", "must be one of x, y, diagonal, smaller, larger (got '" + axis + "')");

    if (props.has("fov")) {
        if (props.has("focalLength")) props.fail("focalLength", "cannot be combined with 'fov'");
        fov_ = props.getFloat("fov");
        if (!(fov_ > 0 && fov_ < 180)) props.fail("fov", "must lie strictly between 0 and 180 degrees");
    } else {
        fov_ = focalLengthToDiagonalFov(props);
        fovAxis_ = FovAxis::Diagonal;  // as in Mitsuba, fovAxis only applies to fov
    }

    film_ = nestedFilm(props, ctx);
    const SamplerSettings sampler = nestedSampler(props);
    sampleCount_ = sampler.sampleCount();
    sampleSequence_ = sampler.sequence();
    updateProjection();
}

void ProjectiveCamera::setThinLens(double apertureRadius, double focusDistance) {
    apertureRadius_ = apertureRadius;
    focusDistance_ = focusDistance;
    updateProjection();
}

void ProjectiveCamera::configure(const Scene &) { updateProjection(); }

// Mitsuba's PerspectiveCamera::configure: the fov is converted to a horizontal one using the aspect ratio
// of the full film, and the crop window selects part of the image plane.
void ProjectiveCamera::updateProjection() {
    const double width = film_->width(), height = film_->height(), aspect = width / height;
    FovAxis axis = fovAxis_;
    if (axis == FovAxis::Smaller) axis = aspect > 1 ? FovAxis::Y : FovAxis::X;
    if (axis == FovAxis::Larger) axis = aspect > 1 ? FovAxis::X : FovAxis::Y;
    const double t = std::tan(0.5 * degToRad(fov_));
    switch (axis) {
        case FovAxis::Y:
            tanX_ = t * aspect;
            break;
        case FovAxis::Diagonal:
            tanX_ = t / std::sqrt(1.0 + 1.0 / (aspect * aspect));
            break;
        default:
            tanX_ = t;
            break;
    }
    tanY_ = tanX_ / aspect;
    xFovDeg_ = radToDeg(2.0 * std::atan(tanX_));
    const double cropArea = (2.0 * tanX_ * film_->cropWidth() / width) * (2.0 * tanY_ * film_->cropHeight() / height);
    invImageArea_ = 1.0 / cropArea;
    // The affine maps between raster positions and the planes z = 1 and z = focusDistance, as products with
    // constants: every camera ray and every connection to the lens goes through them, and their divisions
    // were a chain of three in importance() (issue 17).
    planeScale_ = Vec2(2.0 * tanX_ / width, 2.0 * tanY_ / height);
    planeOrigin_ = Vec2(tanX_ - planeScale_.x * film_->cropX(), tanY_ - planeScale_.y * film_->cropY());
    rasterScale_ = Vec2(0.5 * width / (tanX_ * focusDistance_), 0.5 * height / (tanY_ * focusDistance_));
    rasterOrigin_ = Vec2(0.5 * width - film_->cropX(), 0.5 * height - film_->cropY());
    aperturePdf_ = deltaAperture() ? 0.0 : 1.0 / (kPi * apertureRadius_ * apertureRadius_);
}

Vec3 ProjectiveCamera::aperturePoint(const Vec2 &u) const {
    if (deltaAperture()) return Vec3(0.0);
    const Vec2 disk = warp::squareToUniformDiskConcentric(u);
    return {disk.x * apertureRadius_, disk.y * apertureRadius_, 0.0};
}

Vec3 ProjectiveCamera::toLocalPoint(const Vec3 &p) const {
    return deltaAperture() ? Vec3(0.0) : worldToLocal_.point(p);
}

// x = tan(fov_x / 2) (1 - 2 fx / width) for the film position fx = raster.x + cropX, and likewise y.
Vec3 ProjectiveCamera::rasterToPlane(const Vec2 &raster) const {
    return {planeOrigin_.x - planeScale_.x * raster.x, planeOrigin_.y - planeScale_.y * raster.y, 1.0};
}

double ProjectiveCamera::importance(const Vec3 &a, const Vec3 &d, Vec2 &raster) const {
    if (!(d.z > 0)) return 0.0;
    // Where the ray meets the plane of focus, which is where raster positions are defined (rasterToPlane's
    // inverse, scaled by the focus distance); for the pinhole any plane would do (a = 0, focus distance 1).
    const double invCos = 1.0 / d.z, t = (focusDistance_ - a.z) * invCos;
    raster.x = rasterOrigin_.x - rasterScale_.x * (a.x + d.x * t);
    raster.y = rasterOrigin_.y - rasterScale_.y * (a.y + d.y * t);
    if (!(raster.x >= 0 && raster.x <= film_->cropWidth() && raster.y >= 0 && raster.y <= film_->cropHeight()))
        return 0.0;
    return invImageArea_ * invCos * invCos * invCos;
}

Spectrum ProjectiveCamera::sampleRay(Ray &ray, const Vec2 &raster, const Vec2 &aperture) const {
    const Vec3 a = aperturePoint(aperture);
    const Vec3 d = normalize(rasterToPlane(raster) * focusDistance_ - a);
    // The clip planes are planes of constant camera-space depth.
    const double invZ = 1.0 / d.z;
    ray = Ray(toWorld().point(a), normalize(toWorld().vector(d)), nearClip_ * invZ, farClip_ * invZ);
    return Spectrum(1.0);
}

Spectrum ProjectiveCamera::samplePosition(PositionSample &ps, const Vec2 &u) const {
    ps.p = toWorld().point(aperturePoint(u));
    ps.n = forward();
    ps.measure = deltaAperture() ? Measure::Discrete : Measure::Area;
    ps.pdf = pdfPosition(ps);
    return Spectrum(1.0);
}

// The position factor of the importance is the aperture density itself, so sampling it has weight 1.
Spectrum ProjectiveCamera::evalPosition(const PositionSample &ps) const { return Spectrum(pdfPosition(ps)); }

double ProjectiveCamera::pdfPosition(const PositionSample &ps) const {
    if (deltaAperture()) return ps.measure == Measure::Discrete ? 1.0 : 0.0;
    return ps.measure == Measure::Area ? aperturePdf() : 0.0;
}

Spectrum ProjectiveCamera::sampleDirection(DirectionSample &ds, PositionSample &ps, const Vec2 &raster) const {
    const Vec3 a = toLocalPoint(ps.p);
    const Vec3 d = normalize(rasterToPlane(raster) * focusDistance_ - a);
    ds.d = normalize(toWorld().vector(d));
    ds.measure = Measure::SolidAngle;
    Vec2 unused;
    ds.pdf = importance(a, d, unused);
    ps.uv = raster;
    return Spectrum(ds.pdf > 0 ? 1.0 : 0.0);
}

// evalDirection = We * cos = pdfDirection: see projective.h.
Spectrum ProjectiveCamera::evalDirection(const DirectionSample &ds, const PositionSample &ps) const {
    return Spectrum(pdfDirection(ds, ps));
}

Spectrum ProjectiveCamera::evalDirectionAndPdf(const DirectionSample &ds, const PositionSample &ps, double &pdf) const {
    pdf = pdfDirection(ds, ps);
    return Spectrum(pdf);
}

double ProjectiveCamera::pdfDirection(const DirectionSample &ds, const PositionSample &ps) const {
    if (ds.measure != Measure::SolidAngle) return 0.0;
    Vec2 unused;
    return importance(toLocalPoint(ps.p), normalize(worldToLocal_.vector(ds.d)), unused);
}

Spectrum ProjectiveCamera::sampleDirect(DirectSample &ds, const Vec2 &u) const {
    ds.object = this;
    ds.pdf = 0;
    const Vec3 ref = worldToLocal_.point(ds.ref);
    if (ref.z < nearClip_ || ref.z > farClip_) return Spectrum(0.0);
    const Vec3 a = aperturePoint(u);
    Vec3 d = ref - a;
    const double dist = d.length();
    d = d / dist;
    const double value = importance(a, d, ds.uv);
    if (value == 0) return Spectrum(0.0);
    ds.p = toWorld().point(a);
    ds.n = forward();
    ds.dist = dist;
    ds.d = (ds.p - ds.ref) / dist;
    if (deltaAperture()) {
        ds.pdf = 1.0;
        ds.measure = Measure::Discrete;
    } else {
        ds.pdf = aperturePdf() * dist * dist / d.z;
        ds.measure = Measure::SolidAngle;
    }
    return Spectrum(value / (dist * dist));
}

double ProjectiveCamera::pdfDirect(const DirectSample &ds) const {
    if (deltaAperture()) return ds.measure == Measure::Discrete ? 1.0 : 0.0;
    const double cosTheta = -dot(forward(), ds.d);
    if (!(cosTheta > 0)) return 0.0;
    if (ds.measure == Measure::SolidAngle) return aperturePdf() * ds.dist * ds.dist / cosTheta;
    return ds.measure == Measure::Area ? aperturePdf() : 0.0;
}

bool ProjectiveCamera::rasterPosition(const Vec3 &p, const Vec3 &d, Vec2 &raster) const {
    return importance(toLocalPoint(p), normalize(worldToLocal_.vector(d)), raster) > 0;
}

bool ProjectiveCamera::intersectAperture(const Ray &ray, PositionSample &ps, double &t) const {
    if (deltaAperture()) return false;
    const Vec3 o = worldToLocal_.point(ray.o), d = worldToLocal_.vector(ray.d);
    if (!(d.z < 0)) return false;  // only light arriving from the scene side enters the lens
    const double tHit = -o.z / d.z;
    if (!(tHit > ray.tmin && tHit < ray.tmax)) return false;
    const Vec3 hit(o.x + d.x * tHit, o.y + d.y * tHit, 0.0);
    if (hit.x * hit.x + hit.y * hit.y > apertureRadius_ * apertureRadius_) return false;
    t = tHit;
    ps.p = toWorld().point(hit);
    ps.n = forward();
    ps.measure = Measure::Area;
    ps.pdf = aperturePdf();
    importance(hit, normalize(-d), ps.uv);
    return true;
}

}  // namespace pf
