#include "scene/shape.h"

#include "bsdf/bsdf.h"
#include "emitter/emitter.h"
#include "scene/medium.h"
#include "scene/plugins.h"

namespace pf {

namespace {

template <typename T>
std::shared_ptr<T> childAs(const Properties &props, const std::shared_ptr<Object> &obj, const char *what) {
    if (!obj) return nullptr;
    auto typed = std::dynamic_pointer_cast<T>(obj);
    if (!typed) throw SceneError(obj->location(), props.pluginName() + ": the nested object is not a " + what);
    return typed;
}

// Creates one of the BSDFs that Mitsuba assigns to shapes declared without one.
std::shared_ptr<BSDF> defaultBSDF(const Properties &props, const char *type, const Spectrum *reflectance) {
    const PluginFactory *factory = findPlugin(ObjectKind::BSDF, type);
    if (!factory) props.fail(std::string("the default '") + type + "' BSDF is not available");
    Properties p(ObjectKind::BSDF, type, props.location());
    if (reflectance) p.set("reflectance", Properties::Type::Spectrum, *reflectance, props.location());
    auto bsdf = std::dynamic_pointer_cast<BSDF>((*factory)(p, LoadContext{}));
    if (!bsdf) props.fail(std::string("the default '") + type + "' BSDF could not be created");
    return bsdf;
}

}  // namespace

void Shape::configureCommon(const Properties &props) {
    // The rectangle plugin turns a rectangle with `portal` into a Portal (scene/portal.h) before it gets here.
    if (props.getBool("portal", false))
        props.fail("portal",
                   "only a rectangle can be a portal (a portal must be planar), not a '" + props.pluginName() + "'");
    const auto emitters = props.children(ObjectKind::Emitter);
    if (emitters.size() > 1) props.fail("a shape can carry at most one emitter");
    if (!emitters.empty()) {
        emitter_ = childAs<Emitter>(props, emitters[0], "emitter");
        if (!emitter_->isOnSurface())
            throw SceneError(emitter_->location(),
                             props.pluginName() + ": only area emitters can be attached to shapes");
        if (emitter_->shape())
            throw SceneError(emitter_->location(),
                             props.pluginName() + ": this emitter is already attached to a shape");
        emitter_->setShape(this);
    }
    const auto bsdfs = props.children(ObjectKind::BSDF);
    if (bsdfs.size() > 1) props.fail("a shape can carry at most one BSDF");
    if (!bsdfs.empty()) bsdf_ = childAs<BSDF>(props, bsdfs[0], "BSDF");
    interior_ = childAs<Medium>(props, props.child(ObjectKind::Medium, "interior"), "medium");
    exterior_ = childAs<Medium>(props, props.child(ObjectKind::Medium, "exterior"), "medium");
    if (props.has("causticCaster")) causticCaster_ = props.getBool("causticCaster");
    if (props.has("causticReceiver")) causticReceiver_ = props.getBool("causticReceiver");

    // Mitsuba 0.6 (Shape::configure): emitters without a BSDF absorb everything, medium boundaries without
    // one are index-matched (null), and any other shape gets a 50% diffuse reflector.
    if (!bsdf_) {
        const Spectrum black(0.0), grey(0.5);
        if (emitter_)
            bsdf_ = defaultBSDF(props, "diffuse", &black);
        else if (interior_ || exterior_)
            bsdf_ = defaultBSDF(props, "null", nullptr);
        else
            bsdf_ = defaultBSDF(props, "diffuse", &grey);
    }
    if (emitter_ && bsdf_->isNull()) props.fail("an emitter cannot have an index-matched (null) BSDF");
}

void Shape::sampleDirect(DirectSample &ds, const Vec2 &u) const {
    PositionSample ps;
    samplePosition(ps, u);
    ds.p = ps.p;
    ds.n = ps.n;
    ds.uv = ps.uv;
    ds.measure = Measure::SolidAngle;
    const Vec3 d = ps.p - ds.ref;
    const double dist2 = d.lengthSquared();
    ds.dist = std::sqrt(dist2);
    ds.d = ds.dist > 0 ? d / ds.dist : Vec3();
    // Area density to solid angle at ref: p_w = p_A r^2 / |cos theta| (pbrt-v3 §5.5.3), with |cos theta| =
    // |n . (p - ref)| / r: p_A r^3 / |n . (p - ref)|, whose division waits for the square root only, not for
    // the normalized direction as well.
    const double projected = absDot(ds.n, d);
    ds.pdf = projected > 0 ? ps.pdf * dist2 * ds.dist / projected : 0.0;
}

double Shape::pdfDirect(const DirectSample &ds) const {
    const double cosine = absDot(ds.n, ds.d);
    if (!(cosine > 0) || !(ds.dist > 0)) return 0.0;
    PositionSample ps;
    ps.p = ds.p;
    ps.n = ds.n;
    ps.uv = ds.uv;
    ps.shape = this;
    return pdfPosition(ps) * ds.dist * ds.dist / cosine;
}

}  // namespace pf
