// Mitsuba 0.6's cylinder: the open side surface (no caps) of radius `radius` around the segment from
// `p0` to `p1` (defaults (0,0,0), (0,0,1), 1), then `toWorld`. The transform must keep the cross-section
// circular (rotations, translations, uniform scaling, and any scaling along the axis); elliptic
// cylinders are refused. Parameterization: u = phi / 2pi around the axis, v = distance along the axis /
// length; the angle phi is measured in a frame built from the axis (Duff et al. 2017), so the seam may
// lie elsewhere than in Mitsuba.
#include "scene/plugins.h"
#include "shape/analytic.h"

namespace pf {

namespace {

class Cylinder final : public AnalyticShape {
public:
    explicit Cylinder(const Properties &props) : flipNormals_(props.getBool("flipNormals", false)) {
        const Vec3 p0 = props.getPoint("p0", Vec3(0, 0, 0)), p1 = props.getPoint("p1", Vec3(0, 0, 1));
        const double radius = props.getFloat("radius", 1.0);
        if (!(radius > 0)) props.fail("radius", "must be positive");
        const Vec3 axis = p1 - p0;
        if (!(axis.length() > 0)) props.fail("p1", "must differ from p0");
        Vec3 s, t;
        coordinateSystem(normalize(axis), s, t);
        set(props.getTransform("toWorld", Transform()), p0, p1, s * radius, t * radius, props, "toWorld");
        configureCommon(props);
    }

    // Infinite cylinder x^2 + y^2 = r^2 in the local frame, clipped to 0 <= z <= length. The discriminant
    // uses the distance of the axis to the ray's line, as for the sphere (Ray Tracing Gems, ch. 7).
    bool intersectRay(const Ray &ray, double tmin, double tmax, double &t) const override {
        const Vec3 o = toLocal(ray.o - p0_), d = toLocal(ray.d);
        const double a = d.x * d.x + d.y * d.y, b = o.x * d.x + o.y * d.y;
        if (!(a > 0)) return false;
        const double fx = o.x - d.x * (b / a), fy = o.y - d.y * (b / a);
        const double c = o.x * o.x + o.y * o.y - radius_ * radius_;
        double t0, t1;
        if (!solveQuadratic(a, b, c, a * (radius_ * radius_ - fx * fx - fy * fy), t0, t1)) return false;
        for (const double root : {t0, t1}) {
            const double z = o.z + root * d.z;
            if (root > tmin && root < tmax && z >= 0 && z <= length_) {
                t = root;
                return true;
            }
        }
        return false;
    }

    void fillIntersection(const Ray &ray, double t, uint32_t, const Vec2 &, Intersection &its) const override {
        double tt;
        if (intersectRay(ray, ray.tmin, kInfinity, tt)) t = tt;
        its.t = t;
        const Vec3 local = toLocal(ray(t) - p0_);
        fillSurface(std::atan2(local.y, local.x), local.z, its);
    }

    AABB bbox() const override {
        // Each end circle extends r sqrt(1 - a_i^2) along world axis i.
        const Vec3 ext(radius_ * safeSqrt(1 - axis_.x * axis_.x), radius_ * safeSqrt(1 - axis_.y * axis_.y),
                       radius_ * safeSqrt(1 - axis_.z * axis_.z));
        AABB b;
        for (const Vec3 &c : {p0_, p0_ + axis_ * length_}) {
            b.expand(c - ext);
            b.expand(c + ext);
        }
        return b;
    }
    double surfaceArea() const override { return 2.0 * kPi * radius_ * length_; }

    void samplePosition(PositionSample &ps, const Vec2 &u) const override {
        Intersection its;
        fillSurface(2.0 * kPi * u.y, u.x * length_, its);
        ps.p = its.p;
        ps.n = its.n;
        ps.uv = its.uv;
        ps.pdf = 1.0 / surfaceArea();
        ps.measure = Measure::Area;
        ps.shape = this;
    }

    std::shared_ptr<Shape> transformedCopy(const Transform &toWorld, const Properties &where) const override {
        auto copy = std::make_shared<Cylinder>(*this);
        copy->set(toWorld, p0_, p0_ + axis_ * length_, s_ * radius_, t_ * radius_, where, "toWorld");
        return copy;
    }

private:
    Vec3 toLocal(const Vec3 &v) const { return {dot(v, s_), dot(v, t_), dot(v, axis_)}; }

    // The cylinder around p0 -> p1 whose end circle is spanned by the radial vectors rs, rt, under
    // `toWorld`; refuses transforms that make the cross-section elliptic or tilt it.
    void set(const Transform &toWorld, const Vec3 &p0, const Vec3 &p1, const Vec3 &rs, const Vec3 &rt,
             const Properties &props, const std::string &param) {
        p0_ = toWorld.point(p0);
        const Vec3 axis = toWorld.point(p1) - p0_, ws = toWorld.vector(rs), wt = toWorld.vector(rt);
        length_ = axis.length();
        radius_ = ws.length();
        if (!(length_ > 0) || !(radius_ > 0) || !std::isfinite(length_) || !std::isfinite(radius_) || !p0_.isFinite())
            props.fail(param, "the cylinder is degenerate or not finite");
        axis_ = axis / length_;
        s_ = ws / radius_;
        t_ = wt / radius_;
        const double tol = 1e-6;
        if (std::abs(wt.length() / radius_ - 1.0) > tol || std::abs(dot(s_, t_)) > tol ||
            std::abs(dot(s_, axis_)) > tol || std::abs(dot(t_, axis_)) > tol)
            props.fail(param, "the cylinder's cross-section must stay a circle perpendicular to its axis");
    }

    // p(u, v) = p0 + v L a + r (cos phi s + sin phi t), phi = 2 pi u; the normal is the radial direction.
    void fillSurface(double phi, double z, Intersection &its) const {
        if (phi < 0) phi += 2.0 * kPi;
        const double cosP = std::cos(phi), sinP = std::sin(phi);
        const Vec3 radial = s_ * cosP + t_ * sinP, tangent = t_ * cosP - s_ * sinP;
        its.p = p0_ + axis_ * z + radial * radius_;
        its.uv = Vec2(phi * kInvTwoPi, z / length_);
        its.dpdu = tangent * (2.0 * kPi * radius_);
        its.dpdv = axis_ * length_;
        const double sign = flipNormals_ ? -1.0 : 1.0;
        its.n = radial * sign;
        its.dndu = tangent * (2.0 * kPi * sign);
        its.dndv = Vec3();
        its.shFrame = Frame::fromNormalTangent(its.n, its.dpdu);
        its.shape = this;
        its.primIndex = 0;
    }

    bool flipNormals_;
    Vec3 p0_, axis_, s_, t_;
    double length_ = 1.0, radius_ = 1.0;
};

}  // namespace

std::shared_ptr<Object> createCylinder(const Properties &props, const LoadContext &) {
    return std::make_shared<Cylinder>(props);
}

}  // namespace pf
