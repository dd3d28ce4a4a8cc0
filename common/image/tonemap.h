// ldrfilm's tone mapping (Mitsuba 0.6's tonemapMethod, gamma, exposure, key, burn): linear radiance to
// display values in [0, 1], before the PNG's 8-bit quantisation.
//
// `gamma`: radiance times 2^exposure, then the transfer curve (gamma = -1: sRGB, else a pure power
// 1/gamma). `reinhard`: the global photographic operator of Reinhard et al. 2002 ("Photographic tone
// reproduction for digital images", §3, eqs. 1-4): the log-average luminance Lbar = exp(mean(log(delta +
// Lw))) is mapped to `key` (eq. 2: L = key / Lbar * Lw), and L to Ld = L (1 + L / Lwhite²) / (1 + L)
// (eq. 4), Lwhite being the smallest luminance mapped to white. With burn = 0 Lwhite is the image's
// largest scaled luminance, so that nothing saturates; burn in (0, 1] lowers it to (1 - burn) times that
// (at burn = 1 to a thousandth), letting highlights burn out. Colours keep their ratios (each channel
// times Ld / Lw), then the transfer curve applies as for `gamma`; exposure is not used.
#pragma once
#include <vector>

#include "image/bitmap.h"

namespace pf {

struct ToneMap {
    enum class Method { Gamma, Reinhard };
    Method method = Method::Gamma;
    double exposure = 0.0, gamma = -1.0;  // exposure in stops; gamma -1: sRGB
    double key = 0.18, burn = 0.0;        // Reinhard's key value and Mitsuba's burn
};

// Display values in [0, 1], 3 per pixel (NaN and negative radiance become 0).
std::vector<double> toneMap(const Bitmap &img, const ToneMap &t);

}  // namespace pf
