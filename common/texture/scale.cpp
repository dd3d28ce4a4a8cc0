// Mitsuba 0.6's scale texture (src/textures/scale.cpp): a nested texture, or a constant `value`,
// multiplied by `scale` (a float or a spectrum, default 1).
#include "scene/plugins.h"
#include "texture/texture.h"

namespace pf {

namespace {

class ScaleTexture final : public Texture {
public:
    ScaleTexture(std::shared_ptr<Texture> nested, const Spectrum &scale) : nested_(std::move(nested)), scale_(scale) {}

    Spectrum eval(const Intersection &its) const override { return nested_->eval(its) * scale_; }
    Spectrum average() const override { return nested_->average() * scale_; }
    Spectrum maximum() const override { return nested_->maximum() * scale_; }
    bool isConstant() const override { return nested_->isConstant(); }
    void evalGradient(const Intersection &its, Spectrum &dfdu, Spectrum &dfdv) const override {
        nested_->evalGradient(its, dfdu, dfdv);
        dfdu *= scale_;
        dfdv *= scale_;
    }

private:
    std::shared_ptr<Texture> nested_;
    Spectrum scale_;
};

}  // namespace

std::shared_ptr<Object> createScaleTexture(const Properties &props, const LoadContext &) {
    const Spectrum scale = props.getSpectrum("scale", Spectrum(1.0));
    // Mitsuba asserts a positive scale; a negative one would turn reflectances negative.
    if (scale.min() < 0) props.fail("scale", "must not be negative");
    // Like Mitsuba's addChild, the nested texture may carry any name (or none).
    const auto children = props.children(ObjectKind::Texture);
    if (children.size() > 1) props.fail("takes exactly one nested texture");
    std::shared_ptr<Texture> nested;
    if (!children.empty()) {
        if (props.has("value")) props.fail("value", "given together with a nested texture");
        nested = std::dynamic_pointer_cast<Texture>(children.front());
        if (!nested) props.fail("the nested object is not a texture");
    } else if (props.has("value")) {
        nested = std::make_shared<ConstantTexture>(props.getSpectrum("value"));
    } else {
        props.fail("needs a nested texture or a 'value' spectrum");
    }
    return std::make_shared<ScaleTexture>(std::move(nested), scale);
}

}  // namespace pf
