#include "emitter/latlong_map.h"

#include <cmath>
#include <stdexcept>

namespace pf {

namespace {

Vec2 directionToUV(const Vec3 &v) {
    double u = std::atan2(v.x, -v.z) * kInvTwoPi;
    if (u < 0) u += 1.0;
    // atan2 rather than acos(v.y): acos loses half the digits near the poles.
    return {u, std::atan2(std::hypot(v.x, v.z), v.y) * kInvPi};
}

}  // namespace

LatLongMap::LatLongMap(Bitmap map) : map_(std::move(map)) {
    if (map_.width <= 0 || map_.height <= 0) throw std::invalid_argument("the environment map is empty");
    std::vector<double> weights(static_cast<size_t>(map_.width) * map_.height);
    double total = 0;
    for (int y = 0; y < map_.height; ++y) {
        const double sinTheta = std::sin(kPi * (y + 0.5) / map_.height);
        for (int x = 0; x < map_.width; ++x) {
            const Spectrum s = map_.get(x, y);
            if (!s.isValid()) throw std::invalid_argument("the environment map has negative or non-finite pixels");
            total += weights[static_cast<size_t>(y) * map_.width + x] = s.luminance() * sinTheta;
        }
    }
    // Mitsuba refuses a black map too.
    if (!(total > 0)) throw std::invalid_argument("the environment map is completely black");
    dist_ = Distribution2D(weights, static_cast<size_t>(map_.width), static_cast<size_t>(map_.height));
}

Spectrum LatLongMap::eval(const Vec3 &v) const {
    const Vec2 uv = directionToUV(v);
    return map_.get(column(uv.x), row(uv.y));
}

Vec3 LatLongMap::sample(const Vec2 &u, double &pdf) const {
    double pdfUV = 0;
    const Vec2 uv = dist_.sample(u, &pdfUV);
    const double theta = kPi * uv.y, phi = 2.0 * kPi * uv.x;
    const double sinTheta = std::sin(theta);
    pdf = sinTheta > 0 ? pdfUV / (2.0 * kPi * kPi * sinTheta) : 0.0;
    return {std::sin(phi) * sinTheta, std::cos(theta), -std::cos(phi) * sinTheta};
}

double LatLongMap::pdf(const Vec3 &v) const {
    const double sinTheta = std::hypot(v.x, v.z);
    if (!(sinTheta > 0)) return 0.0;
    return dist_.pdf(directionToUV(v)) / (2.0 * kPi * kPi * sinTheta);
}

// Each pixel spans 2 pi / W in phi and cos(theta0) - cos(theta1) in cos theta.
Spectrum LatLongMap::integral() const {
    Spectrum sum(0.0);
    for (int y = 0; y < map_.height; ++y) {
        const double band = std::cos(kPi * y / map_.height) - std::cos(kPi * (y + 1) / map_.height);
        Spectrum rowSum(0.0);
        for (int x = 0; x < map_.width; ++x) rowSum += map_.get(x, y);
        sum += rowSum * band;
    }
    return sum * (2.0 * kPi / map_.width);
}

}  // namespace pf
