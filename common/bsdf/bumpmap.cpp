// Mitsuba 0.6 "bumpmap": perturbs the shading frame of a nested BSDF with a height map h(u, v) given as
// a nested texture (its colour average; scale it with a "scale" texture as in Mitsuba). The bumped
// surface p + h n has the tangents
//     dp'/du = dp/du - n (n . dp/du) + n dh/du,    dp'/dv likewise      (Blinn 1978, first order)
// whose cross product is the new shading normal, flipped to the side of the geometric normal. The
// nested BSDF is queried in that frame; as in Mitsuba, directions that change side between the two
// frames get no contribution, and the cosine of eval() is the one about the bumped normal.
#include "bsdf/bsdf_util.h"
#include "bsdf/factories.h"

namespace pf {

namespace {

class BumpMap final : public BSDF {
public:
    BumpMap(std::shared_ptr<Texture> height, std::shared_ptr<BSDF> nested)
        : height_(std::move(height)), nested_(std::move(nested)) {
        flags_ = nested_->flags() | BSDFFlags::SpatiallyVarying | BSDFFlags::Anisotropic;
    }

    Spectrum eval(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
                  Measure measure) const override {
        const Intersection bumped = perturb(its);
        const Vec3 woB = toBumped(its, bumped, wo);
        if (wo.z * woB.z <= 0) return Spectrum(0.0);
        return nested_->eval(ctx, bumped, toBumped(its, bumped, wi), woB, measure);
    }

    double pdf(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, const Vec3 &wo,
               Measure measure) const override {
        const Intersection bumped = perturb(its);
        const Vec3 woB = toBumped(its, bumped, wo);
        if (wo.z * woB.z <= 0) return 0.0;
        return nested_->pdf(ctx, bumped, toBumped(its, bumped, wi), woB, measure);
    }

    Spectrum sample(const BSDFContext &ctx, const Intersection &its, const Vec3 &wi, BSDFSample &bs, double u1,
                    const Vec2 &u2) const override {
        const Intersection bumped = perturb(its);
        const Spectrum weight = nested_->sample(ctx, bumped, toBumped(its, bumped, wi), bs, u1, u2);
        if (weight.isBlack()) return weight;
        const Vec3 woB = bs.wo;
        bs.wo = its.toLocal(bumped.toWorld(woB));
        if (bs.wo.z * woB.z <= 0) return Spectrum(0.0);
        return weight;
    }

    double roughness(const Intersection &its, uint32_t lobe) const override {
        return nested_->roughness(perturb(its), lobe);
    }
    Spectrum diffuseReflectance(const Intersection &its) const override {
        return nested_->diffuseReflectance(perturb(its));
    }

private:
    // The intersection with the bumped shading frame (and wi expressed in it).
    Intersection perturb(const Intersection &its) const {
        Spectrum dhdu, dhdv;
        height_->evalGradient(its, dhdu, dhdv);
        const Vec3 &n = its.shFrame.n;
        const Vec3 dpdu = its.dpdu + n * (dhdu.average() - dot(n, its.dpdu));
        const Vec3 dpdv = its.dpdv + n * (dhdv.average() - dot(n, its.dpdv));
        Vec3 nb = cross(dpdu, dpdv);
        const double len = nb.length();
        // Without a usable parameterization (zero or parallel tangents) the frame stays as it is.
        if (!(len > 0) || !nb.isFinite()) return its;
        nb = nb / len;
        if (dot(nb, its.n) < 0) nb = -nb;
        Intersection bumped = its;
        bumped.shFrame = Frame::fromNormalTangent(nb, dpdu);
        bumped.wi = toBumped(its, bumped, its.wi);
        return bumped;
    }

    static Vec3 toBumped(const Intersection &its, const Intersection &bumped, const Vec3 &v) {
        return bumped.toLocal(its.toWorld(v));
    }

    std::shared_ptr<Texture> height_;
    std::shared_ptr<BSDF> nested_;
};

}  // namespace

std::shared_ptr<Object> createBumpMapBSDF(const Properties &props, const LoadContext &) {
    const std::vector<std::shared_ptr<Object>> textures = props.children(ObjectKind::Texture);
    if (textures.size() != 1)
        props.fail("bumpmap expects exactly one nested texture (the height map), got " +
                   std::to_string(textures.size()));
    return std::make_shared<BumpMap>(std::static_pointer_cast<Texture>(textures.front()),
                                     nestedBSDFs(props, 1, 1).front());
}

}  // namespace pf
