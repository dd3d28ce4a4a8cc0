// Mitsuba 0.6's sphere: `center` and `radius` (default: the unit sphere at the origin) followed by an
// optional `toWorld`, which must be a similarity (Mitsuba silently takes the radius from the x axis; a
// non-uniformly scaled sphere is refused here instead of rendered wrongly). The parameterization is
// Mitsuba's, in the sphere's own frame (the rotation part of the transform): u = phi / 2pi, v = theta / pi.
#include "core/warp.h"
#include "scene/plugins.h"
#include "shape/analytic.h"

namespace pf {

namespace {

class Sphere final : public AnalyticShape {
public:
    explicit Sphere(const Properties &props) : flipNormals_(props.getBool("flipNormals", false)) {
        const double radius = props.getFloat("radius", 1.0);
        if (!(radius > 0)) props.fail("radius", "must be positive");
        const Transform toWorld = props.getTransform("toWorld", Transform()) *
                                  Transform::translate(props.getPoint("center", Vec3(0.0))) *
                                  Transform::scale(Vec3(radius));
        setFromTransform(toWorld, props, "toWorld");
        configureCommon(props);
    }

    bool intersectRay(const Ray &ray, double tmin, double tmax, double &t) const override {
        // Haines et al. (Ray Tracing Gems, ch. 7): the discriminant from the distance of the centre to
        // the ray's line, which does not cancel for small spheres far away.
        const Vec3 oc = ray.o - center_;
        const double a = ray.d.lengthSquared(), b = dot(oc, ray.d);
        const Vec3 f = oc - ray.d * (b / a);
        const double c = oc.lengthSquared() - radius_ * radius_;
        const double disc = a * (radius_ * radius_ - f.lengthSquared());
        double t0, t1;
        if (!solveQuadratic(a, b, c, disc, t0, t1)) return false;
        if (t0 > tmin && t0 < tmax) {
            t = t0;
            return true;
        }
        if (t1 > tmin && t1 < tmax) {
            t = t1;
            return true;
        }
        return false;
    }

    void fillIntersection(const Ray &ray, double t, uint32_t, const Vec2 &, Intersection &its) const override {
        double tt;
        // Embree's (float) distance is only a hint: redo the hit in double; keep it if the double
        // intersection disagrees (a grazing ray that Embree accepted).
        if (intersectRay(ray, ray.tmin, kInfinity, tt)) t = tt;
        its.t = t;
        fillSurface(ray(t), its);
    }

    AABB bbox() const override {
        AABB b;
        b.expand(center_ - Vec3(radius_));
        b.expand(center_ + Vec3(radius_));
        return b;
    }
    double surfaceArea() const override { return 4.0 * kPi * radius_ * radius_; }

    void samplePosition(PositionSample &ps, const Vec2 &u) const override {
        Intersection its;
        fillSurface(center_ + warp::squareToUniformSphere(u) * radius_, its);
        ps.p = its.p;
        ps.n = its.n;
        ps.uv = its.uv;
        ps.pdf = 1.0 / surfaceArea();
        ps.measure = Measure::Area;
        ps.shape = this;
    }

    // From outside, only the cone of directions subtended by the sphere is sampled, uniformly (pbrt-v3
    // §14.2.2; the construction of the point on the sphere is pbrt-v4's, which stays accurate for
    // distant spheres). Each direction of the cone meets the sphere's near side exactly once. From inside
    // (or on) the sphere every point is visible and area sampling is used.
    void sampleDirect(DirectSample &ds, const Vec2 &u) const override {
        double oneMinusCosMax;
        if (!outside(ds.ref, oneMinusCosMax)) {
            Shape::sampleDirect(ds, u);
            return;
        }
        const Vec3 toCenter = center_ - ds.ref;
        const double dc = toCenter.length();
        const double sinThetaMax = radius_ / dc;
        const double oneMinusCos = u.x * oneMinusCosMax;
        const double cosTheta = 1.0 - oneMinusCos, sin2Theta = oneMinusCos * (2.0 - oneMinusCos);
        // Angle at the centre between the reference point and the sampled point.
        const double cosAlpha =
            sin2Theta / sinThetaMax + cosTheta * safeSqrt(1.0 - sin2Theta / (sinThetaMax * sinThetaMax));
        const double sinAlpha = safeSqrt(1.0 - cosAlpha * cosAlpha);
        const double phi = 2.0 * kPi * u.y;
        const Frame frame(toCenter / dc);
        const Vec3 outward = frame.toWorld(Vec3(sinAlpha * std::cos(phi), sinAlpha * std::sin(phi), -cosAlpha));
        Intersection its;
        fillSurface(center_ + outward * radius_, its);
        ds.p = its.p;
        ds.n = its.n;
        ds.uv = its.uv;
        const Vec3 d = ds.p - ds.ref;
        ds.dist = d.length();
        ds.d = d / ds.dist;
        ds.pdf = 1.0 / (2.0 * kPi * oneMinusCosMax);
        ds.measure = Measure::SolidAngle;
    }

    // From outside, points on the far side are never sampled: their density is zero (a ray reaching one
    // through a transmissive light is then weighted entirely by the strategy that found it).
    double pdfDirect(const DirectSample &ds) const override {
        double oneMinusCosMax;
        if (!outside(ds.ref, oneMinusCosMax)) return Shape::pdfDirect(ds);
        if (dot(ds.p - center_, ds.ref - ds.p) < 0) return 0.0;
        return 1.0 / (2.0 * kPi * oneMinusCosMax);
    }

    std::shared_ptr<Shape> transformedCopy(const Transform &toWorld, const Properties &where) const override {
        auto copy = std::make_shared<Sphere>(*this);
        copy->setFromTransform(toWorld * objectToWorld_, where, "toWorld");
        return copy;
    }

private:
    // Takes centre, radius and orientation from a similarity transform of the unit sphere.
    void setFromTransform(const Transform &toWorld, const Properties &props, const std::string &param) {
        center_ = toWorld.point(Vec3(0.0));
        const Vec3 x = toWorld.vector(Vec3(1, 0, 0)), y = toWorld.vector(Vec3(0, 1, 0)),
                   z = toWorld.vector(Vec3(0, 0, 1));
        radius_ = x.length();
        const double tol = 1e-6 * radius_ * radius_;
        if (std::abs(y.lengthSquared() - radius_ * radius_) > tol ||
            std::abs(z.lengthSquared() - radius_ * radius_) > tol || std::abs(dot(x, y)) > tol ||
            std::abs(dot(x, z)) > tol || std::abs(dot(y, z)) > tol)
            props.fail(param, "a sphere can only be rotated, translated and scaled uniformly");
        if (!center_.isFinite() || !(radius_ > 0) || !std::isfinite(radius_))
            props.fail(param, "the sphere is degenerate or not finite");
        frame_ = Frame(x / radius_, y / radius_, z / radius_);
        objectToWorld_ = toWorld;
    }

    // True if p is strictly outside; then also 1 - cos(theta_max) of the subtended cone, written so that
    // it keeps its precision for small cones.
    bool outside(const Vec3 &p, double &oneMinusCosMax) const {
        const double dc2 = (center_ - p).lengthSquared(), r2 = radius_ * radius_;
        if (!(dc2 > r2)) return false;
        const double sin2Max = r2 / dc2;
        oneMinusCosMax = sin2Max / (1.0 + std::sqrt(1.0 - sin2Max));
        return true;
    }

    // Surface point nearest to p (p is projected onto the sphere) with Mitsuba's parameterization
    // p(u, v) = c + r R (sin theta cos phi, sin theta sin phi, cos theta), phi = 2 pi u, theta = pi v.
    void fillSurface(const Vec3 &p, Intersection &its) const {
        Vec3 rel = p - center_;
        const double len = rel.length();
        const Vec3 local = len > 0 ? frame_.toLocal(rel / len) : Vec3(0, 0, 1);
        const double theta = safeAcos(local.z);
        double phi = std::atan2(local.y, local.x);
        if (phi < 0) phi += 2.0 * kPi;
        const double sinT = std::sin(theta), cosT = std::cos(theta), sinP = std::sin(phi), cosP = std::cos(phi);
        const Vec3 outward = frame_.toWorld(Vec3(sinT * cosP, sinT * sinP, cosT));
        its.p = center_ + outward * radius_;
        its.uv = Vec2(phi * kInvTwoPi, theta * kInvPi);
        its.dpdu = frame_.toWorld(Vec3(-sinT * sinP, sinT * cosP, 0.0)) * (2.0 * kPi * radius_);
        its.dpdv = frame_.toWorld(Vec3(cosT * cosP, cosT * sinP, -sinT)) * (kPi * radius_);
        const double sign = flipNormals_ ? -1.0 : 1.0;
        its.n = outward * sign;
        its.dndu = its.dpdu * (sign / radius_);
        its.dndv = its.dpdv * (sign / radius_);
        its.shFrame = Frame::fromNormalTangent(its.n, its.dpdu);
        its.shape = this;
        its.primIndex = 0;
    }

    bool flipNormals_;
    Vec3 center_;
    double radius_ = 1.0;
    Frame frame_;
    Transform objectToWorld_;
};

}  // namespace

std::shared_ptr<Object> createSphere(const Properties &props, const LoadContext &) {
    return std::make_shared<Sphere>(props);
}

}  // namespace pf
