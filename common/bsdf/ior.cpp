#include "bsdf/ior.h"

#include <algorithm>
#include <cctype>

namespace pf {

namespace {

std::string toLower(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
    return s;
}

std::string joinNames(const std::vector<std::string> &names) {
    std::string out;
    for (const std::string &n : names) out += (out.empty() ? "" : ", ") + n;
    return out;
}

struct DielectricEntry {
    const char *name;
    double ior;
};

// Mitsuba 0.6 src/bsdfs/ior.h: values at ~589 nm and 0-20 degrees Celsius, mostly from Hecht, Optics
// (4th edition).
constexpr DielectricEntry kDielectrics[] = {
    {"vacuum", 1.0},      {"helium", 1.000036},        {"hydrogen", 1.000132},
    {"air", 1.000277},    {"carbon dioxide", 1.00045}, {"water", 1.3330},
    {"acetone", 1.36},    {"ethanol", 1.361},          {"carbon tetrachloride", 1.461},
    {"glycerol", 1.4729}, {"benzene", 1.501},          {"silicone oil", 1.52045},
    {"bromine", 1.661},   {"water ice", 1.31},         {"fused quartz", 1.458},
    {"pyrex", 1.470},     {"acrylic glass", 1.49},     {"polypropylene", 1.49},
    {"bk7", 1.5046},      {"sodium chloride", 1.544},  {"amber", 1.55},
    {"pet", 1.5750},      {"diamond", 2.419},
};

struct ConductorEntry {
    const char *name;
    Spectrum eta, k;
};

// Mitsuba 0.6 ships measured spectra data/ior/<name>.{eta,k}.spd (Palik's handbook via the Luxpop
// database, as in pbrt). In RGB mode Mitsuba converts each spectrum once by integrating it against the
// CIE 1931 matching functions over 360-830 nm (normalized by the integral of y-bar) and mapping XYZ to
// linear sRGB (Spectrum::fromContinuousSpectrum / fromXYZ). These are those RGB values, as tabulated
// by Tungsten's ComplexIorData (checked here against an independent integration of Cu.eta.spd with the
// 5 nm CIE table: agreement to 6e-4). The conversion can leave tiny negative values for almost
// non-absorbing materials; they are kept, as Mitsuba keeps them.
const ConductorEntry kConductors[] = {
    {"a-C", {2.9440999183, 2.2271502925, 1.9681668794}, {0.8874329109, 0.7993216383, 0.8152862927}},
    {"Ag", {0.1552646489, 0.1167232965, 0.1383806959}, {4.8283433224, 3.1222459278, 2.1469504455}},
    {"Al", {1.6574599595, 0.8803689579, 0.5212287346}, {9.2238691996, 6.2695232477, 4.8370012281}},
    {"AlAs", {3.6051023902, 3.2329365777, 2.2175611545}, {0.0006670247, -0.0004999400, 0.0074261204}},
    {"AlAs_palik", {3.6051023902, 3.2329365777, 2.2175611545}, {0.0006670247, -0.0004999400, 0.0074261204}},
    {"AlSb", {-0.0485225705, 4.1427547893, 4.6697691348}, {-0.0363741915, 0.0937665154, 1.3007390124}},
    {"AlSb_palik", {-0.0485225705, 4.1427547893, 4.6697691348}, {-0.0363741915, 0.0937665154, 1.3007390124}},
    {"Au", {0.1431189557, 0.3749570432, 1.4424785571}, {3.9831604247, 2.3857207478, 1.6032152899}},
    {"Be", {4.1850592788, 3.1850604423, 2.7840913457}, {3.8354398268, 3.0101260162, 2.8690088743}},
    {"Be_palik", {4.1850592788, 3.1850604423, 2.7840913457}, {3.8354398268, 3.0101260162, 2.8690088743}},
    {"Cr", {4.3696828663, 2.9167024892, 1.6547005413}, {5.2064337956, 4.2313645277, 3.7549467933}},
    {"CsI", {2.1449030413, 1.7023164587, 1.6624194173}, {0.0, 0.0, 0.0}},
    {"CsI_palik", {2.1449030413, 1.7023164587, 1.6624194173}, {0.0, 0.0, 0.0}},
    {"Cu", {0.2004376970, 0.9240334304, 1.1022119527}, {3.9129485033, 2.4528477015, 2.1421879552}},
    {"Cu2O", {3.5492833755, 2.9520622449, 2.7369202137}, {0.1132179294, 0.1946659670, 0.6001681264}},
    {"Cu2O_palik", {3.5492833755, 2.9520622449, 2.7369202137}, {0.1132179294, 0.1946659670, 0.6001681264}},
    {"CuO", {3.2453822204, 2.4496293965, 2.1974114493}, {0.5202739621, 0.5707372756, 0.7172250613}},
    {"CuO_palik", {3.2453822204, 2.4496293965, 2.1974114493}, {0.5202739621, 0.5707372756, 0.7172250613}},
    {"Cu_palik", {0.2126840430, 0.9199880064, 1.1024078212}, {3.9215626225, 2.4571489948, 2.1366534268}},
    {"d-C", {2.7112524747, 2.3185812849, 2.2288565009}, {0.0, 0.0, 0.0}},
    {"d-C_palik", {2.7112524747, 2.3185812849, 2.2288565009}, {0.0, 0.0, 0.0}},
    {"Hg", {2.3989314904, 1.4400254917, 0.9095512090}, {6.3276269444, 4.3719414152, 3.4217899270}},
    {"Hg_palik", {2.3989314904, 1.4400254917, 0.9095512090}, {6.3276269444, 4.3719414152, 3.4217899270}},
    {"HgTe", {4.7795267752, 3.2309984581, 2.6600252401}, {1.6319827058, 1.5808189339, 1.7295753852}},
    {"HgTe_palik", {4.7795267752, 3.2309984581, 2.6600252401}, {1.6319827058, 1.5808189339, 1.7295753852}},
    {"Ir", {3.0864098394, 2.0821938440, 1.6178866805}, {5.5921510077, 4.0671757150, 3.2672611269}},
    {"Ir_palik", {3.0864098394, 2.0821938440, 1.6178866805}, {5.5921510077, 4.0671757150, 3.2672611269}},
    {"K", {0.0640493070, 0.0464100621, 0.0381842017}, {2.1042155920, 1.3489364357, 0.9132113889}},
    {"K_palik", {0.0640493070, 0.0464100621, 0.0381842017}, {2.1042155920, 1.3489364357, 0.9132113889}},
    {"Li", {0.2657871942, 0.1956102432, 0.2209198538}, {3.5401743407, 2.3111306542, 1.6685930000}},
    {"Li_palik", {0.2657871942, 0.1956102432, 0.2209198538}, {3.5401743407, 2.3111306542, 1.6685930000}},
    {"MgO", {2.0895885542, 1.6507224525, 1.5948759692}, {0.0, 0.0, 0.0}},
    {"MgO_palik", {2.0895885542, 1.6507224525, 1.5948759692}, {0.0, 0.0, 0.0}},
    {"Mo", {4.4837010280, 3.5254578255, 2.7760769438}, {4.1111307988, 3.4208716252, 3.1506031404}},
    {"Mo_palik", {4.4837010280, 3.5254578255, 2.7760769438}, {4.1111307988, 3.4208716252, 3.1506031404}},
    {"Na_palik", {0.0602665320, 0.0561412435, 0.0619909494}, {3.1792906496, 2.1124800781, 1.5790940266}},
    {"Nb", {3.4201353595, 2.7901921379, 2.3955856658}, {3.4413817900, 2.7376437930, 2.5799132708}},
    {"Nb_palik", {3.4201353595, 2.7901921379, 2.3955856658}, {3.4413817900, 2.7376437930, 2.5799132708}},
    {"Ni_palik", {2.3672753521, 1.6633583302, 1.4670554172}, {4.4988329911, 3.0501643957, 2.3454274399}},
    {"Rh", {2.5857954933, 1.8601866068, 1.5544279524}, {6.7822927110, 4.7029501026, 3.9760892461}},
    {"Rh_palik", {2.5857954933, 1.8601866068, 1.5544279524}, {6.7822927110, 4.7029501026, 3.9760892461}},
    {"Se", {4.0592611085, 2.8426947380, 2.8207582835}, {0.7543791750, 0.6385150558, 0.5215872029}},
    {"Se_palik", {4.0592611085, 2.8426947380, 2.8207582835}, {0.7543791750, 0.6385150558, 0.5215872029}},
    {"Se-e", {5.7242724833, 4.1653992967, 4.0816099264}, {0.8713747439, 1.1052845009, 1.5647788766}},
    {"Se-e_palik", {5.7242724833, 4.1653992967, 4.0816099264}, {0.8713747439, 1.1052845009, 1.5647788766}},
    {"SiC", {3.1723450205, 2.5259677964, 2.4793623897}, {0.0000007284, -0.0000006859, 0.0000100150}},
    {"SiC_palik", {3.1723450205, 2.5259677964, 2.4793623897}, {0.0000007284, -0.0000006859, 0.0000100150}},
    {"SnTe", {4.5251865890, 1.9811525984, 1.2816819226}, {0.0, 0.0, 0.0}},
    {"SnTe_palik", {4.5251865890, 1.9811525984, 1.2816819226}, {0.0, 0.0, 0.0}},
    {"Ta", {2.0625846607, 2.3930915569, 2.6280684948}, {2.4080467973, 1.7413705864, 1.9470377016}},
    {"Ta_palik", {2.0625846607, 2.3930915569, 2.6280684948}, {2.4080467973, 1.7413705864, 1.9470377016}},
    {"Te", {7.3908396088, 4.4821028985, 2.6370708478}, {3.2561412892, 3.5273908133, 3.2921683116}},
    {"Te_palik", {7.3908396088, 4.4821028985, 2.6370708478}, {3.2561412892, 3.5273908133, 3.2921683116}},
    {"Te-e", {7.5090397678, 4.2964603080, 2.3698732430}, {5.5842076830, 4.9476231084, 3.9975145063}},
    {"Te-e_palik", {7.5090397678, 4.2964603080, 2.3698732430}, {5.5842076830, 4.9476231084, 3.9975145063}},
    {"ThF4", {1.8307187117, 1.4422274283, 1.3876488528}, {0.0, 0.0, 0.0}},
    {"ThF4_palik", {1.8307187117, 1.4422274283, 1.3876488528}, {0.0, 0.0, 0.0}},
    {"TiC", {3.7004673762, 2.8374356509, 2.5823030278}, {3.2656905818, 2.3515586388, 2.1727857800}},
    {"TiC_palik", {3.7004673762, 2.8374356509, 2.5823030278}, {3.2656905818, 2.3515586388, 2.1727857800}},
    {"TiN", {1.6484691607, 1.1504482522, 1.3797795097}, {3.3684596226, 1.9434888540, 1.1020123347}},
    {"TiN_palik", {1.6484691607, 1.1504482522, 1.3797795097}, {3.3684596226, 1.9434888540, 1.1020123347}},
    {"TiO2", {3.4566203131, 2.8017076558, 2.9051485020}, {0.0001026662, -0.0000897534, 0.0006356902}},
    {"TiO2_palik", {3.4566203131, 2.8017076558, 2.9051485020}, {0.0001026662, -0.0000897534, 0.0006356902}},
    {"TiO2-e", {3.1065574823, 2.5131551146, 2.5823844157}, {0.0000289537, -0.0000251484, 0.0001775555}},
    {"TiO2-e_palik", {3.1065574823, 2.5131551146, 2.5823844157}, {0.0000289537, -0.0000251484, 0.0001775555}},
    {"VC", {3.6575665991, 2.7527298065, 2.5326814570}, {3.0683516659, 2.1986687713, 1.9631816252}},
    {"VC_palik", {3.6575665991, 2.7527298065, 2.5326814570}, {3.0683516659, 2.1986687713, 1.9631816252}},
    {"VN", {2.8656011588, 2.1191817791, 1.9400767149}, {3.0323264950, 2.0561075580, 1.6162930914}},
    {"VN_palik", {2.8656011588, 2.1191817791, 1.9400767149}, {3.0323264950, 2.0561075580, 1.6162930914}},
    {"V_palik", {4.2775126218, 3.5131538236, 2.7611257461}, {3.4911844504, 2.8893580874, 3.1116965117}},
    {"W", {4.3707029924, 3.3002972445, 2.9982666528}, {3.5006778591, 2.6048652781, 2.2731930614}},
    // Mitsuba 0.6 special case: an ideal mirror (conductor.cpp, materialName == "none").
    {"none", {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}},
};

bool isNumeric(Properties::Type t) { return t == Properties::Type::Float || t == Properties::Type::Integer; }

}  // namespace

std::optional<double> lookupDielectricIOR(const std::string &name) {
    const std::string lower = toLower(name);
    for (const DielectricEntry &e : kDielectrics)
        if (lower == e.name) return e.ior;
    return std::nullopt;
}

std::vector<std::string> dielectricIORNames() {
    std::vector<std::string> names;
    for (const DielectricEntry &e : kDielectrics) names.emplace_back(e.name);
    return names;
}

double readDielectricIOR(const Properties &props, const std::string &name, const std::string &defaultName) {
    double ior;
    if (props.has(name) && isNumeric(props.type(name))) {
        ior = props.getFloat(name);
    } else {
        const std::string value = props.getString(name, defaultName);
        const std::optional<double> found = lookupDielectricIOR(value);
        if (!found)
            props.fail(name, "unknown index of refraction \"" + value +
                                 "\"; give a number or one of: " + joinNames(dielectricIORNames()));
        ior = *found;
    }
    if (!(ior > 0.0)) props.fail(name, "the index of refraction must be positive");
    return ior;
}

std::optional<ConductorIOR> lookupConductorIOR(const std::string &name) {
    const std::string lower = toLower(name);
    for (const ConductorEntry &e : kConductors)
        if (lower == toLower(e.name)) return ConductorIOR{e.eta, e.k};
    return std::nullopt;
}

std::vector<std::string> conductorIORNames() {
    std::vector<std::string> names;
    for (const ConductorEntry &e : kConductors) names.emplace_back(e.name);
    return names;
}

ConductorIOR readConductorIOR(const Properties &props) {
    const std::string material = props.getString("material", "Cu");
    const std::optional<ConductorIOR> preset = lookupConductorIOR(material);
    if (!preset)
        props.fail("material",
                   "unknown conductor \"" + material + "\"; valid presets are: " + joinNames(conductorIORNames()));
    ConductorIOR ior{props.getSpectrum("eta", preset->eta), props.getSpectrum("k", preset->k)};
    if (props.has("eta") && ior.eta.min() < 0) props.fail("eta", "must be non-negative");
    if (props.has("k") && ior.k.min() < 0) props.fail("k", "must be non-negative");
    const double extEta = readDielectricIOR(props, "extEta", "air");
    ior.eta = ior.eta / extEta;
    ior.k = ior.k / extEta;
    return ior;
}

}  // namespace pf
