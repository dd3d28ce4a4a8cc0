#include "bsdf/bsdf_util.h"

namespace pf {

std::shared_ptr<Texture> readUnitTexture(const Properties &props, const std::string &name, const Spectrum &def) {
    std::shared_ptr<Texture> tex = props.getTexture(name, def);
    const Spectrum hi = tex->maximum();
    if (hi.max() > 1.0 || (tex->isConstant() && hi.min() < 0.0))
        props.fail(name, "must lie in [0, 1] for the model to conserve energy");
    return tex;
}

std::vector<std::shared_ptr<BSDF>> nestedBSDFs(const Properties &props, size_t minCount, size_t maxCount) {
    std::vector<std::shared_ptr<BSDF>> out;
    for (const std::shared_ptr<Object> &obj : props.children(ObjectKind::BSDF))
        out.push_back(std::static_pointer_cast<BSDF>(obj));
    if (out.size() < minCount || out.size() > maxCount) {
        const std::string expected = minCount == maxCount
                                         ? std::to_string(minCount)
                                         : std::to_string(minCount) + " or " + std::to_string(maxCount);
        props.fail("expected " + expected + " nested BSDF" + (maxCount > 1 ? "s" : "") + ", got " +
                   std::to_string(out.size()));
    }
    return out;
}

}  // namespace pf
