// Parameter helpers shared by the path endpoints: emitters and sensors.
#pragma once
#include <cmath>
#include <string>

#include "core/spectrum.h"
#include "core/transform.h"
#include "scene/properties.h"

namespace pf {

// A toWorld transform made of rotations, reflections and translations only. Cameras, spot lights,
// directional lights and environment maps derive directions and solid-angle densities from it, which a
// scale or shear would silently distort (Mitsuba 0.6 refuses scale factors there for the same reason).
// The tolerance (1e-3 on M^T M) lets rotation matrices written out with six significant digits, as
// exporters do, still load; the directions derived from the transform are normalized anyway.
inline Transform rigidTransform(const Properties &props, const std::string &name) {
    const Transform t = props.getTransform(name, Transform());
    const Matrix4 &m = t.matrix();
    if (m.m[3][0] != 0 || m.m[3][1] != 0 || m.m[3][2] != 0 || m.m[3][3] != 1)
        props.fail(name, "must be an affine transform (no projection)");
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double d = 0;  // entry (i, j) of M^T M, which is the identity exactly when M is orthonormal
            for (int k = 0; k < 3; ++k) d += m.m[k][i] * m.m[k][j];
            if (std::abs(d - (i == j ? 1.0 : 0.0)) > 1e-3)
                props.fail(name, "scale and shear factors are not allowed here (rotations and translations only)");
        }
    return t;
}

// A spectrum-valued parameter that must be non-negative in every channel (radiance, intensity, ...).
inline Spectrum nonNegativeSpectrum(const Properties &props, const std::string &name, const Spectrum &def) {
    const Spectrum s = props.getSpectrum(name, def);
    if (!s.isValid()) props.fail(name, "must be non-negative");
    return s;
}

}  // namespace pf
