// Mitsuba 0.6 "homogeneous": constant absorption and scattering coefficients and a nested phase
// function (isotropic by default).
//
// Parameters as in Mitsuba 0.6 (src/medium/homogeneous.cpp, materials.h, librender/medium.cpp): either
// sigmaA and sigmaS, or sigmaT and albedo, or a `material` preset (default skin1, which also fills in a
// coefficient the file leaves out); `g` (default: the preset's) reduces sigma_s to (1 - g) sigma_s;
// `scale` multiplies the coefficients; `mediumSamplingWeight` is the probability of trying to sample an
// interaction at all.
//
// Free-flight sampling follows Mitsuba's "balance" strategy, which is unbiased for a chromatic sigma_t:
// with probability w a colour channel c is picked uniformly and a distance drawn from
// sigma_t[c] exp(-sigma_t[c] t); the density of the mixture is therefore the channel average
//     pdfSuccess(t) = w * avg_c sigma_t[c] exp(-sigma_t[c] t),
//     pdfFailure(L) = w * avg_c exp(-sigma_t[c] L) + (1 - w),
// and the integrator weights an interaction by sigma_s T(t) / pdfSuccess and a crossing by
// T(L) / pdfFailure (pbrt-v3 §15.2.1 does the same with w = 1). w defaults to the largest single-scattering
// albedo, at least 0.5 when the medium scatters at all and 0 when it only absorbs: a purely absorbing
// medium then attenuates deterministically instead of wasting samples on interactions that carry no
// light. A homogeneous density depends only on the segment length, so pdfSuccessRev = pdfSuccess.
//
// Distances are measured in units of the ray parameter: ray.d must be a unit vector.
#include <algorithm>
#include <cctype>

#include "medium/media.h"
#include "scene/properties.h"

namespace pf {

namespace {

struct Preset {
    const char *name;         // matched case-insensitively
    Spectrum sigmaS, sigmaA;  // per millimetre
    Spectrum g;               // mean cosine of the measured phase function
};

// Mitsuba 0.6's medium presets (src/medium/materials.h): the fits of Jensen et al. 2001, "A Practical Model
// for Subsurface Light Transport" (no anisotropy data), and the measurements of Narasimhan et al. 2006,
// "Acquiring Scattering Properties of Participating Media by Dilution".
const Preset kPresets[] = {
    {"apple", {2.29, 2.39, 1.97}, {0.0030, 0.0034, 0.046}, {0, 0, 0}},
    {"chicken1", {0.15, 0.21, 0.38}, {0.0015, 0.077, 0.19}, {0, 0, 0}},
    {"chicken2", {0.19, 0.25, 0.32}, {0.0018, 0.088, 0.20}, {0, 0, 0}},
    {"cream", {7.38, 5.47, 3.15}, {0.0002, 0.0028, 0.0163}, {0, 0, 0}},
    {"ketchup", {0.18, 0.07, 0.03}, {0.061, 0.97, 1.45}, {0, 0, 0}},
    {"marble", {2.19, 2.62, 3.00}, {0.0021, 0.0041, 0.0071}, {0, 0, 0}},
    {"potato", {0.68, 0.70, 0.55}, {0.0024, 0.0090, 0.12}, {0, 0, 0}},
    {"skimmilk", {0.70, 1.22, 1.90}, {0.0014, 0.0025, 0.0142}, {0, 0, 0}},
    {"skin1", {0.74, 0.88, 1.01}, {0.032, 0.17, 0.48}, {0, 0, 0}},
    {"skin2", {1.09, 1.59, 1.79}, {0.013, 0.070, 0.145}, {0, 0, 0}},
    {"spectralon", {11.6, 20.4, 14.9}, {0.0, 0.0, 0.0}, {0, 0, 0}},
    {"wholemilk", {2.55, 3.21, 3.77}, {0.0011, 0.0024, 0.014}, {0, 0, 0}},
    {"lowfat milk", {13.1157, 15.4445, 17.9572}, {0.00287, 0.00575, 0.01150}, {0.932, 0.902, 0.859}},
    {"reduced milk", {13.7335, 15.6003, 17.8007}, {0.00256, 0.00511, 0.01278}, {0.819, 0.797, 0.746}},
    {"regular milk", {18.2052, 20.3826, 22.3698}, {0.00153, 0.00460, 0.01993}, {0.750, 0.714, 0.681}},
    {"espresso", {7.78262, 8.13050, 8.53875}, {4.79838, 6.57512, 8.84925}, {0.907, 0.896, 0.880}},
    {"mint mocha coffee", {3.51133, 4.14383, 5.59667}, {3.77200, 5.82283, 7.82000}, {0.910, 0.907, 0.914}},
    {"lowfat soy milk", {2.03838, 2.32875, 3.90281}, {0.00144, 0.00719, 0.03594}, {0.850, 0.853, 0.842}},
    {"regular soy milk", {4.66325, 5.20183, 8.74575}, {0.00192, 0.00958, 0.06517}, {0.873, 0.858, 0.832}},
    {"lowfat chocolate milk", {9.83710, 11.4954, 13.1629}, {0.01150, 0.03680, 0.15640}, {0.934, 0.927, 0.916}},
    {"regular chocolate milk", {10.5685, 13.1416, 15.2202}, {0.01006, 0.04313, 0.14375}, {0.862, 0.838, 0.806}},
    {"coke", {0.00254, 0.00299, 0.0}, {0.10014, 0.16503, 0.24680}, {0.965, 0.972, 0.0}},
    {"pepsi", {0.00083, 0.00203, 0.0}, {0.09164, 0.14158, 0.20729}, {0.926, 0.979, 0.0}},
    {"sprite", {0.00011, 0.00014, 0.00014}, {0.00189, 0.00183, 0.00200}, {0.943, 0.953, 0.952}},
    {"gatorade", {0.03668, 0.04488, 0.05742}, {0.02479, 0.01929, 0.00888}, {0.933, 0.933, 0.935}},
    {"chardonnay", {0.00021, 0.00033, 0.00048}, {0.01078, 0.01186, 0.02400}, {0.914, 0.958, 0.975}},
    {"white zinfandel", {0.00022, 0.00033, 0.00046}, {0.01207, 0.01618, 0.01984}, {0.919, 0.943, 0.972}},
    {"merlot", {0.00081, 0.0, 0.0}, {0.11632, 0.25191, 0.29434}, {0.974, 0.0, 0.0}},
    {"budweiser beer", {0.00029, 0.00055, 0.00059}, {0.01149, 0.02491, 0.05779}, {0.917, 0.956, 0.982}},
    {"coors light beer", {0.00062, 0.00127, 0.0}, {0.00616, 0.01398, 0.03498}, {0.918, 0.966, 0.0}},
    {"clorox", {0.02731, 0.03302, 0.03695}, {0.00335, 0.01489, 0.02630}, {0.912, 0.905, 0.892}},
    {"apple juice", {0.00257, 0.00311, 0.00413}, {0.01296, 0.02374, 0.05218}, {0.947, 0.949, 0.945}},
    {"cranberry juice", {0.00196, 0.00238, 0.00301}, {0.03944, 0.09422, 0.12426}, {0.947, 0.951, 0.974}},
    {"grape juice", {0.00138, 0.0, 0.0}, {0.10404, 0.23958, 0.29325}, {0.961, 0.0, 0.0}},
    {"ruby grapefruit juice", {0.15496, 0.15391, 0.15995}, {0.08587, 0.18314, 0.25262}, {0.929, 0.929, 0.931}},
    {"white grapefruit juice", {0.50499, 0.52742, 0.75282}, {0.01380, 0.01883, 0.05678}, {0.548, 0.545, 0.565}},
    {"shampoo", {0.00797, 0.00874, 0.01127}, {0.01411, 0.04569, 0.06172}, {0.910, 0.905, 0.920}},
    {"strawberry shampoo", {0.00215, 0.00245, 0.00253}, {0.01449, 0.05796, 0.07582}, {0.927, 0.935, 0.994}},
    {"head & shoulders shampoo", {0.26747, 0.27696, 0.29574}, {0.08462, 0.15688, 0.20365}, {0.911, 0.896, 0.884}},
    {"lemon tea powder", {0.74489, 0.83823, 1.00158}, {2.42881, 4.57573, 7.21270}, {0.946, 0.946, 0.949}},
    {"orange juice powder", {0.00193, 0.00213, 0.00226}, {0.00145, 0.00344, 0.00786}, {0.919, 0.918, 0.922}},
    {"pink lemonade powder", {0.00123, 0.00133, 0.00131}, {0.00116, 0.00237, 0.00320}, {0.902, 0.902, 0.904}},
    {"cappuccino powder", {12.2094, 16.4659, 29.2727}, {35.8441, 49.5470, 61.0844}, {0.849, 0.843, 0.926}},
    {"salt powder", {0.13805, 0.15677, 0.17865}, {0.28415, 0.32570, 0.34148}, {0.802, 0.793, 0.821}},
    {"sugar powder", {0.00282, 0.00315, 0.00393}, {0.01264, 0.03105, 0.05012}, {0.921, 0.919, 0.931}},
    {"suisse mocha powder", {30.0848, 33.4452, 38.7191}, {17.5020, 27.0044, 35.4334}, {0.907, 0.894, 0.888}},
    {"pacific ocean surface water", {0.00180, 0.00183, 0.00228}, {0.03184, 0.03132, 0.03015}, {0.902, 0.825, 0.914}},
};

// exp(-sigma * length) for one channel; a channel without extinction transmits fully even along an
// infinite segment (where 0 * inf would give NaN).
double channelTransmittance(double sigma, double length) { return sigma > 0 ? std::exp(-sigma * length) : 1.0; }

Spectrum validCoefficient(const Properties &props, const std::string &name, const Spectrum &def) {
    const Spectrum s = props.getSpectrum(name, def);
    if (!s.isValid()) props.fail(name, "must be non-negative in every channel");
    return s;
}

class HomogeneousMedium final : public Medium {
public:
    explicit HomogeneousMedium(const Properties &props) {
        readCoefficients(props);
        readSamplingWeight(props);
        const auto phases = props.children(ObjectKind::Phase);
        if (phases.size() > 1) props.fail("a medium takes at most one nested phase function");
        phase_ = phases.empty() ? makeIsotropicPhase() : std::dynamic_pointer_cast<PhaseFunction>(phases.front());
        if (!phase_) props.fail("the nested object is not a phase function");
    }

    bool sampleDistance(const Ray &ray, double u, MediumSample &ms) const override {
        const double length = ray.tmax - ray.tmin;
        double distance = kInfinity;
        if (u < weight_) {
            // One uniform number picks the channel and, rescaled, drives the exponential inversion.
            double v = u / weight_ * 3.0;
            const int channel = std::min(static_cast<int>(v), 2);
            v -= channel;
            if (sigmaT_[channel] > 0) distance = -std::log1p(-v) / sigmaT_[channel];
        }
        const bool interaction = distance < length;
        fill(ray, interaction ? distance : length, ms);
        return interaction;
    }

    Spectrum evalTransmittance(const Ray &ray) const override { return transmittance(ray.tmax - ray.tmin); }

    // Both densities are cheap here, so they are filled whatever `interaction` asks for.
    void evalDistancePdf(const Ray &ray, bool, MediumSample &ms) const override { fill(ray, ray.tmax - ray.tmin, ms); }

    Spectrum sigmaS() const override { return sigmaS_; }
    Spectrum sigmaT() const override { return sigmaT_; }

private:
    void readCoefficients(const Properties &props) {
        if (props.has("densityMultiplier") || props.has("sizeMultiplier"))
            props.fail(props.has("densityMultiplier") ? "densityMultiplier" : "sizeMultiplier",
                       "was renamed to 'scale' in Mitsuba 0.5");
        const bool hasAS = props.has("sigmaA") || props.has("sigmaS");
        const bool hasTAlbedo = props.has("sigmaT") || props.has("albedo");
        if (hasAS && hasTAlbedo)
            props.fail(props.has("sigmaT") ? "sigmaT" : "albedo",
                       "give either sigmaA and sigmaS, or sigmaT and albedo, not a mix of both");
        if ((hasAS || hasTAlbedo) && props.has("material"))
            props.fail("material", "give either a material preset or scattering coefficients, not both");

        std::string material = props.getString("material", "skin1");
        std::transform(material.begin(), material.end(), material.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        const auto preset =
            std::find_if(std::begin(kPresets), std::end(kPresets), [&](const Preset &p) { return material == p.name; });
        if (preset == std::end(kPresets)) {
            std::string names;
            for (const Preset &p : kPresets) names += (names.empty() ? "" : ", ") + std::string(p.name);
            props.fail("material", "unknown preset '" + material + "' (available: " + names + ")");
        }
        // Mitsuba scales the presets' per-millimetre values by 100.
        sigmaS_ = preset->sigmaS * 100.0;
        sigmaA_ = preset->sigmaA * 100.0;

        if (hasAS) {
            sigmaS_ = validCoefficient(props, "sigmaS", sigmaS_);
            sigmaA_ = validCoefficient(props, "sigmaA", sigmaA_);
        } else if (hasTAlbedo) {
            const Spectrum sigmaT = validCoefficient(props, "sigmaT", sigmaA_ + sigmaS_);
            const Spectrum albedo = props.getSpectrum("albedo", sigmaS_ / (sigmaA_ + sigmaS_));
            if (!albedo.isValid() || albedo.max() > 1.0) props.fail("albedo", "must lie in [0, 1] in every channel");
            sigmaS_ = albedo * sigmaT;
            sigmaA_ = sigmaT - sigmaS_;
        }
        // Mitsuba 0.6 (Medium::Medium) does not turn the presets' anisotropy, or a `g` given here, into a
        // phase function: it replaces sigma_s by the reduced coefficient (1 - g) sigma_s.
        const Spectrum g = props.getSpectrum("g", preset->g);
        if (!(g.min() > -1.0 && g.max() < 1.0)) props.fail("g", "must lie strictly between -1 and 1");
        const double scale = props.getFloat("scale", 1.0);
        if (!(scale >= 0)) props.fail("scale", "must be non-negative");
        sigmaS_ *= (Spectrum(1.0) - g) * scale;
        sigmaA_ *= scale;
        sigmaT_ = sigmaA_ + sigmaS_;
    }

    void readSamplingWeight(const Properties &props) {
        const std::string strategy = props.getString("strategy", "balance");
        if (strategy != "balance") props.fail("strategy", "only Mitsuba's 'balance' strategy is supported");
        double albedo = 0;
        for (int c = 0; c < 3; ++c)
            if (sigmaT_[c] > 0) albedo = std::max(albedo, sigmaS_[c] / sigmaT_[c]);
        weight_ = props.getFloat("mediumSamplingWeight", albedo > 0 ? std::max(albedo, 0.5) : 0.0);
        if (!(weight_ >= 0 && weight_ <= 1)) props.fail("mediumSamplingWeight", "must lie in [0, 1]");
        // With w = 0 no interaction is ever sampled, so in-scattered light would silently go missing.
        if (weight_ == 0 && sigmaS_.max() > 0)
            props.fail("mediumSamplingWeight", "must be positive for a medium that scatters");
    }

    Spectrum transmittance(double length) const {
        return {channelTransmittance(sigmaT_.r, length), channelTransmittance(sigmaT_.g, length),
                channelTransmittance(sigmaT_.b, length)};
    }

    // Fills ms for the point at distance `distance` from ray.tmin (an interaction there, or the end of
    // the segment when distance = ray.tmax - ray.tmin).
    void fill(const Ray &ray, double distance, MediumSample &ms) const {
        ms.t = ray.tmin + distance;
        ms.p = ray(ms.t);
        ms.transmittance = transmittance(distance);
        ms.sigmaA = sigmaA_;
        ms.sigmaS = sigmaS_;
        double success = 0, failure = 0;
        for (int c = 0; c < 3; ++c) {
            success += sigmaT_[c] * ms.transmittance[c];
            failure += ms.transmittance[c];
        }
        ms.pdfSuccess = ms.pdfSuccessRev = weight_ * success / 3.0;
        ms.pdfFailure = weight_ * failure / 3.0 + (1.0 - weight_);
        ms.medium = this;
    }

    Spectrum sigmaA_, sigmaS_, sigmaT_;
    double weight_ = 0;  // Mitsuba's mediumSamplingWeight
};

}  // namespace

std::shared_ptr<Object> createHomogeneousMedium(const Properties &props, const LoadContext &) {
    return std::make_shared<HomogeneousMedium>(props);
}

}  // namespace pf
