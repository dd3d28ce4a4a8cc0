// Mitsuba 0.6's disk: the unit disk in the z = 0 plane of its local frame, normal +z, under `toWorld`
// (any affine map: the disk may become an ellipse). Parameterization as Mitsuba's: u = r, v = phi / 2pi
// in local polar coordinates; the partials here are the exact ones of that chart (Mitsuba's dp/dv omits
// the factor 2 pi r).
#include "core/warp.h"
#include "scene/plugins.h"
#include "shape/analytic.h"

namespace pf {

namespace {

class Disk final : public AnalyticShape {
public:
    explicit Disk(const Properties &props) : flipNormals_(props.getBool("flipNormals", false)) {
        set(props.getTransform("toWorld", Transform()), props, "toWorld");
        configureCommon(props);
    }

    bool intersectRay(const Ray &ray, double tmin, double tmax, double &t) const override {
        // The local ray keeps the parameter t of the world ray (affine map).
        const Vec3 o = worldToObject_.point(ray.o), d = worldToObject_.vector(ray.d);
        if (d.z == 0) return false;
        const double tt = -o.z / d.z;
        if (!(tt > tmin && tt < tmax)) return false;
        const double x = o.x + tt * d.x, y = o.y + tt * d.y;
        if (x * x + y * y > 1.0) return false;
        t = tt;
        return true;
    }

    void fillIntersection(const Ray &ray, double t, uint32_t, const Vec2 &, Intersection &its) const override {
        double tt;
        if (intersectRay(ray, ray.tmin, kInfinity, tt)) t = tt;
        its.t = t;
        const Vec3 local = worldToObject_.point(ray.o) + worldToObject_.vector(ray.d) * t;
        fillSurface(local.x, local.y, its);
    }

    AABB bbox() const override {
        // The ellipse c + cos(phi) a + sin(phi) b extends sqrt(a_i^2 + b_i^2) along world axis i.
        const Vec3 c = objectToWorld_.point(Vec3(0.0)), a = objectToWorld_.vector(Vec3(1, 0, 0)),
                   b = objectToWorld_.vector(Vec3(0, 1, 0));
        const Vec3 ext(std::hypot(a.x, b.x), std::hypot(a.y, b.y), std::hypot(a.z, b.z));
        AABB box;
        box.expand(c - ext);
        box.expand(c + ext);
        return box;
    }
    double surfaceArea() const override { return area_; }

    // Uniform on the unit disk stays uniform under an affine map.
    void samplePosition(PositionSample &ps, const Vec2 &u) const override {
        const Vec2 q = warp::squareToUniformDiskConcentric(u);
        Intersection its;
        fillSurface(q.x, q.y, its);
        ps.p = its.p;
        ps.n = its.n;
        ps.uv = its.uv;
        ps.pdf = 1.0 / area_;
        ps.measure = Measure::Area;
        ps.shape = this;
    }

    std::shared_ptr<Shape> transformedCopy(const Transform &toWorld, const Properties &where) const override {
        auto copy = std::make_shared<Disk>(*this);
        copy->set(toWorld * objectToWorld_, where, "toWorld");
        return copy;
    }

private:
    void set(const Transform &toWorld, const Properties &props, const std::string &param) {
        objectToWorld_ = toWorld;
        worldToObject_ = toWorld.inverse();
        // The image of the unit disk under the linear part M has area pi |M e_x x M e_y|.
        const Vec3 n = cross(toWorld.vector(Vec3(1, 0, 0)), toWorld.vector(Vec3(0, 1, 0)));
        area_ = kPi * n.length();
        if (!(area_ > 0) || !std::isfinite(area_)) props.fail(param, "the disk is degenerate or not finite");
        normal_ = normalize(toWorld.normal(Vec3(0, 0, 1))) * (flipNormals_ ? -1.0 : 1.0);
    }

    // p(u, v) = M (u cos phi, u sin phi, 0), phi = 2 pi v; a flat surface, so dn = 0.
    void fillSurface(double x, double y, Intersection &its) const {
        const double r = std::sqrt(x * x + y * y);
        double phi = std::atan2(y, x);
        if (phi < 0) phi += 2.0 * kPi;
        const double cosP = std::cos(phi), sinP = std::sin(phi);
        its.p = objectToWorld_.point(Vec3(x, y, 0.0));
        its.uv = Vec2(r, phi * kInvTwoPi);
        its.dpdu = objectToWorld_.vector(Vec3(cosP, sinP, 0.0));
        its.dpdv = objectToWorld_.vector(Vec3(-sinP, cosP, 0.0)) * (2.0 * kPi * r);
        its.n = normal_;
        its.dndu = its.dndv = Vec3();
        its.shFrame = Frame::fromNormalTangent(normal_, its.dpdu);
        its.shape = this;
        its.primIndex = 0;
    }

    bool flipNormals_;
    Transform objectToWorld_, worldToObject_;
    Vec3 normal_;
    double area_ = kPi;
};

}  // namespace

std::shared_ptr<Object> createDisk(const Properties &props, const LoadContext &) {
    return std::make_shared<Disk>(props);
}

}  // namespace pf
