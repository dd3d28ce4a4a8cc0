#include "shape/trianglemesh.h"

#include <algorithm>
#include <cfloat>
#include <map>

#include "core/warp.h"
#include "scene/properties.h"

namespace pf {

namespace {

// Angle between two unit vectors without the cancellation of acos near 0 and pi (Mitsuba's unitAngle).
double unitAngle(const Vec3 &a, const Vec3 &b) {
    return dot(a, b) < 0 ? kPi - 2.0 * safeAsin(0.5 * (a + b).length()) : 2.0 * safeAsin(0.5 * (b - a).length());
}

Vec3 faceNormal(const std::vector<Vec3> &p, const std::array<uint32_t, 3> &tri) {
    return normalize(cross(p[tri[1]] - p[tri[0]], p[tri[2]] - p[tri[0]]));
}

// Smooth vertex normals as the angle-weighted average of the incident face normals (Thuermer and
// Wuethrich 1998, "Computing vertex normals from polygonal facets", the method of Mitsuba's
// TriMesh::computeNormals). Where the weights cancel exactly (a vertex on a zero-thickness fold) the
// normal of the first incident face is used instead of Mitsuba's arbitrary (1, 0, 0).
std::vector<Vec3> angleWeightedNormals(const std::vector<Vec3> &p, const std::vector<std::array<uint32_t, 3>> &tris) {
    std::vector<Vec3> sum(p.size()), fallback(p.size());
    for (const auto &tri : tris) {
        const Vec3 n = faceNormal(p, tri);
        for (int k = 0; k < 3; ++k) {
            const Vec3 &v0 = p[tri[k]];
            const double angle = unitAngle(normalize(p[tri[(k + 1) % 3]] - v0), normalize(p[tri[(k + 2) % 3]] - v0));
            sum[tri[k]] += n * angle;
            if (fallback[tri[k]].isZero()) fallback[tri[k]] = n;
        }
    }
    for (size_t i = 0; i < p.size(); ++i) {
        const double len = sum[i].length();
        sum[i] = len > 0 ? sum[i] / len : fallback[i];
    }
    return sum;
}

// Embree traverses a float copy of the mesh.
bool withinFloatRange(const std::vector<Vec3> &points) {
    for (const Vec3 &p : points)
        if (!(std::abs(p.x) <= FLT_MAX && std::abs(p.y) <= FLT_MAX && std::abs(p.z) <= FLT_MAX)) return false;
    return true;
}

}  // namespace

MeshOptions MeshOptions::fromProperties(const Properties &props) {
    MeshOptions o;
    o.toWorld = props.getTransform("toWorld", Transform());
    o.faceNormals = props.getBool("faceNormals", false);
    o.flipNormals = props.getBool("flipNormals", false);
    return o;
}

MeshOptions MeshOptions::forMeshFile(const Properties &props) {
    MeshOptions o = fromProperties(props);
    o.maxSmoothAngle = props.getFloat("maxSmoothAngle", 0.0);
    if (o.maxSmoothAngle < 0) props.fail("maxSmoothAngle", "must not be negative");
    return o;
}

TriangleMesh::TriangleMesh(const Properties &props, MeshData data, const MeshOptions &opts, const std::string &source) {
    build(std::move(data), opts, source);
    configureCommon(props);
}

void TriangleMesh::build(MeshData data, const MeshOptions &opts, const std::string &source) {
    const SourceLocation where{source, 0};
    const auto fail = [&](const std::string &msg) { throw SceneError(where, msg); };
    const size_t nv = data.positions.size();
    if (nv >= UINT32_MAX) fail("too many vertices (" + std::to_string(nv) + ")");
    if (!data.normals.empty() && data.normals.size() != nv) fail("vertex normal count differs from vertex count");
    if (!data.uvs.empty() && data.uvs.size() != nv) fail("texture coordinate count differs from vertex count");
    for (size_t i = 0; i < nv; ++i)
        if (!data.positions[i].isFinite()) fail("vertex " + std::to_string(i) + " has a non-finite coordinate");
    for (size_t i = 0; i < data.normals.size(); ++i)
        if (!data.normals[i].isFinite()) fail("vertex normal " + std::to_string(i) + " is not finite");
    for (size_t i = 0; i < data.uvs.size(); ++i)
        if (!std::isfinite(data.uvs[i].x) || !std::isfinite(data.uvs[i].y))
            fail("texture coordinate " + std::to_string(i) + " is not finite");
    if (data.triangles.empty()) fail("the mesh has no faces");
    for (size_t t = 0; t < data.triangles.size(); ++t)
        for (uint32_t idx : data.triangles[t])
            if (idx >= nv)
                fail("face " + std::to_string(t) + " refers to vertex " + std::to_string(idx) +
                     ", but there are only " + std::to_string(nv) + " vertices");

    positions_ = std::move(data.positions);
    uvs_ = std::move(data.uvs);
    triangles_ = std::move(data.triangles);
    // File normals are only kept when they are used (Mitsuba discards them for faceNormals and rebuilds
    // them for maxSmoothAngle).
    const bool faceNormals = opts.faceNormals || data.faceNormals;
    if (!faceNormals && !(opts.maxSmoothAngle > 0)) normals_ = std::move(data.normals);
    transformInPlace(opts.toWorld);
    if (!withinFloatRange(positions_)) fail("vertex coordinates exceed the single-precision range of the ray tracer");

    // Zero-area triangles cannot be hit and would give NaN normals; they are dropped (Mitsuba warns).
    std::erase_if(triangles_, [&](const std::array<uint32_t, 3> &tri) {
        const double a =
            cross(positions_[tri[1]] - positions_[tri[0]], positions_[tri[2]] - positions_[tri[0]]).length();
        return !(a > 0) || !std::isfinite(a);
    });
    if (triangles_.empty()) fail("the mesh has no faces of non-zero area");

    if (!normals_.empty()) {
        for (const auto &tri : triangles_)
            for (uint32_t idx : tri)
                if (normals_[idx].isZero()) fail("vertex normal " + std::to_string(idx) + " has zero length");
    } else if (opts.maxSmoothAngle > 0) {
        rebuildCreases(opts.maxSmoothAngle);
    } else if (!faceNormals) {
        normals_ = angleWeightedNormals(positions_, triangles_);
    }
    // Mitsuba turns smooth normals around, and reverses the winding of faceted meshes, whose normals come
    // from the winding.
    if (opts.flipNormals) {
        if (normals_.empty())
            for (auto &tri : triangles_) std::swap(tri[1], tri[2]);
        else
            for (Vec3 &n : normals_) n = -n;
    }
    updateSamplingData();
}

void TriangleMesh::transformInPlace(const Transform &toWorld) {
    for (Vec3 &p : positions_) p = toWorld.point(p);
    for (Vec3 &n : normals_) {
        n = toWorld.normal(n);
        const double len = n.length();
        if (len > 0) n = n / len;
    }
    // A mirroring transform would turn the winding-defined normals of faceted meshes inside out; reversing
    // the winding keeps them pointing where the inverse-transposed vertex normals point (pbrt-v3 §2.8.4).
    if (toWorld.flipsHandedness())
        for (auto &tri : triangles_) std::swap(tri[1], tri[2]);
}

// Mitsuba's TriMesh::rebuildTopology: corners that share a position and texture coordinate are greedily
// clustered by face normal (a corner joins the cluster of the first unclustered corner whose face normal
// is within maxAngle of its own); each cluster becomes one vertex with an angle-weighted normal, so
// creases sharper than maxAngle stay sharp.
void TriangleMesh::rebuildCreases(double maxAngleDeg) {
    const double cosThreshold = std::cos(degToRad(maxAngleDeg));
    std::vector<Vec3> faceN(triangles_.size());
    std::map<std::array<double, 5>, std::vector<size_t>> corners;
    for (size_t t = 0; t < triangles_.size(); ++t) {
        faceN[t] = faceNormal(positions_, triangles_[t]);
        for (int k = 0; k < 3; ++k) {
            const uint32_t i = triangles_[t][k];
            const Vec2 uv = uvs_.empty() ? Vec2() : uvs_[i];
            corners[{positions_[i].x, positions_[i].y, positions_[i].z, uv.x, uv.y}].push_back(3 * t + k);
        }
    }
    std::vector<Vec3> newPositions;
    std::vector<Vec2> newUVs;
    std::vector<std::array<uint32_t, 3>> newTriangles(triangles_.size());
    for (const auto &[key, list] : corners) {
        std::vector<bool> clustered(list.size(), false);
        for (size_t a = 0; a < list.size(); ++a) {
            if (clustered[a]) continue;
            const uint32_t vertex = static_cast<uint32_t>(newPositions.size());
            newPositions.emplace_back(key[0], key[1], key[2]);
            if (!uvs_.empty()) newUVs.emplace_back(key[3], key[4]);
            const Vec3 &n1 = faceN[list[a] / 3];
            for (size_t b = a; b < list.size(); ++b) {
                const Vec3 &n2 = faceN[list[b] / 3];
                if (clustered[b] || !(n1 == n2 || dot(n1, n2) > cosThreshold)) continue;
                newTriangles[list[b] / 3][list[b] % 3] = vertex;
                clustered[b] = true;
            }
        }
    }
    positions_ = std::move(newPositions);
    uvs_ = std::move(newUVs);
    triangles_ = std::move(newTriangles);
    normals_ = angleWeightedNormals(positions_, triangles_);
}

void TriangleMesh::updateSamplingData() {
    std::vector<double> areas(triangles_.size());
    constants_.resize(triangles_.size());
    bbox_ = AABB();
    for (size_t t = 0; t < triangles_.size(); ++t) {
        const auto &tri = triangles_[t];
        const Vec3 e1 = positions_[tri[1]] - positions_[tri[0]], e2 = positions_[tri[2]] - positions_[tri[0]];
        areas[t] = 0.5 * cross(e1, e2).length();
        const InverseChart j = inverseChart(static_cast<uint32_t>(t));
        constants_[t] = {faceNormal(positions_, tri), e1 * j.j00 + e2 * j.j10, e1 * j.j01 + e2 * j.j11};
        for (uint32_t i : tri) bbox_.expand(positions_[i]);
    }
    areaDist_ = Distribution1D(areas);
    area_ = areaDist_.sum();
    invArea_ = 1.0 / area_;

    const bool flat = std::all_of(triangles_.begin(), triangles_.end(), [&](const std::array<uint32_t, 3> &tri) {
        return normals_.empty() || (normals_[tri[0]] == normals_[tri[1]] && normals_[tri[0]] == normals_[tri[2]]);
    });
    flatFrames_.clear();
    if (flat)
        for (size_t t = 0; t < triangles_.size(); ++t)
            flatFrames_.push_back(Frame::fromNormalTangent(
                normals_.empty() ? constants_[t].ng : normalize(normals_[triangles_[t][0]]), constants_[t].dpdu));
    findParallelogram();
}

void TriangleMesh::findParallelogram() {
    parallelogram_.reset();
    if (triangles_.size() != 2 || !(area_ > 0)) return;
    const auto &t0 = triangles_[0], &t1 = triangles_[1];
    const auto inT1 = [&](uint32_t v) { return v == t1[0] || v == t1[1] || v == t1[2]; };
    // The two corners the triangles share are the diagonal p - r; q is triangle 0's third corner, s triangle 1's.
    int shared = 0, qAt = -1;
    for (int k = 0; k < 3; ++k) {
        if (inT1(t0[k]))
            ++shared;
        else
            qAt = k;
    }
    if (shared != 2) return;
    const uint32_t q = t0[static_cast<size_t>(qAt)];
    // Triangle 0 in its own winding as q, r, p: r follows q.
    const uint32_t r = t0[static_cast<size_t>((qAt + 1) % 3)], p = t0[static_cast<size_t>((qAt + 2) % 3)];
    uint32_t s = t1[0];
    for (const uint32_t v : t1)
        if (v != p && v != r) s = v;
    if (s == p || s == r || s == q) return;
    // A parallelogram: q + s = p + r, and so the two triangles have the same area. The tolerance is far below
    // single precision, the ray tracer's: where the corners are off by rounding, the density on each triangle
    // is 1 / (2 area_t) against the 1 / area that pdfPosition gives, a relative difference of the same order.
    const Vec3 &P = positions_[p], &Q = positions_[q], &R = positions_[r], &S = positions_[s];
    const double size = std::max({(Q - P).length(), (S - P).length(), (R - P).length()});
    if (!((Q + S - P - R).length() <= 1e-12 * size) || !(std::abs(areaDist_.pmf(0) - areaDist_.pmf(1)) <= 1e-12))
        return;
    Parallelogram g{};
    for (int t = 0; t < 2; ++t)
        for (int k = 1; k <= 2; ++k) {
            const uint32_t v = triangles_[static_cast<size_t>(t)][static_cast<size_t>(k)];
            g.pick[t][k - 1][v == p ? 0 : v == r ? 2 : 1] = 1.0;
        }
    parallelogram_ = g;
}

unsigned TriangleMesh::addToEmbree(RTCDevice device, RTCScene scene) const {
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto *v = static_cast<float *>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                           3 * sizeof(float), positions_.size()));
    auto *idx = static_cast<uint32_t *>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                3 * sizeof(uint32_t), triangles_.size()));
    if (!v || !idx) {
        rtcReleaseGeometry(geom);
        throw SceneError(location(), "out of memory while building the ray-tracing geometry");
    }
    for (size_t i = 0; i < positions_.size(); ++i)
        for (int k = 0; k < 3; ++k) v[3 * i + k] = static_cast<float>(positions_[i][k]);
    for (size_t t = 0; t < triangles_.size(); ++t)
        for (int k = 0; k < 3; ++k) idx[3 * t + k] = triangles_[t][k];
    rtcCommitGeometry(geom);
    const unsigned id = rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    return id;
}

// Inline in both callers (every mesh hit and every emitter position sample; issue 17): only this file uses it.
inline Vec3 TriangleMesh::surfacePoint(uint32_t prim, double b1, double b2, Vec3 &p, Vec3 &ng, Vec2 &uv) const {
    const auto &tri = triangles_[prim];
    const Vec3 &p0 = positions_[tri[0]], &p1 = positions_[tri[1]], &p2 = positions_[tri[2]];
    const double b0 = 1.0 - b1 - b2;
    p = p0 * b0 + p1 * b1 + p2 * b2;
    ng = constants_[prim].ng;
    uv = uvs_.empty() ? Vec2(b1, b2) : uvs_[tri[0]] * b0 + uvs_[tri[1]] * b1 + uvs_[tri[2]] * b2;
    if (normals_.empty()) return Vec3();
    const Vec3 N = !flatFrames_.empty() ? flatFrames_[prim].n
                                        : normals_[tri[0]] * b0 + normals_[tri[1]] * b1 + normals_[tri[2]] * b2;
    // The geometric normal follows the side the shading normals point to (Mitsuba and pbrt-v3 §3.6.2), so
    // that vertex normals decide the orientation of smooth meshes. The sign needs no normalization of N.
    if (dot(ng, N) < 0) ng = -ng;
    return N;
}

TriangleMesh::InverseChart TriangleMesh::inverseChart(uint32_t prim) const {
    InverseChart j;
    if (uvs_.empty()) return j;
    const auto &tri = triangles_[prim];
    const Vec2 &t0 = uvs_[tri[0]], &t1 = uvs_[tri[1]], &t2 = uvs_[tri[2]];
    const Vec2 d1 = t1 - t0, d2 = t2 - t0;
    const double det = d1.x * d2.y - d1.y * d2.x;
    // A texture mapping that folds the triangle onto (almost) a line has no inverse: the barycentric chart
    // stands in for it, so that dp/du and dp/dv stay a basis of the tangent plane.
    if (std::abs(det) > 1e-10 * (d1.x * d1.x + d1.y * d1.y + d2.x * d2.x + d2.y * d2.y)) {
        j.j00 = d2.y / det;
        j.j01 = -d2.x / det;
        j.j10 = -d1.y / det;
        j.j11 = d1.x / det;
    }
    return j;
}

void TriangleMesh::fillSurface(uint32_t prim, double b1, double b2, Intersection &its) const {
    const Vec3 N = surfacePoint(prim, b1, b2, its.p, its.n, its.uv);
    its.dpdu = constants_[prim].dpdu;
    its.dpdv = constants_[prim].dpdv;
    its.dndu = its.dndv = Vec3();
    its.normalDerivativesPending = !normals_.empty();
    if (!flatFrames_.empty()) {
        its.shFrame = flatFrames_[prim];
    } else {
        const double len = N.length();
        its.shFrame = Frame::fromNormalTangent(len > 0 ? N / len : its.n, its.dpdu);
    }
    its.shape = this;
    its.primIndex = prim;
    its.primUV = Vec2(b1, b2);
}

void TriangleMesh::fillNormalDerivatives(Intersection &its) const {
    if (!its.normalDerivativesPending) return;
    its.normalDerivativesPending = false;
    const auto &tri = triangles_[its.primIndex];
    const double b1 = its.primUV.x, b2 = its.primUV.y, b0 = 1.0 - b1 - b2;
    const Vec3 &n0 = normals_[tri[0]], &n1 = normals_[tri[1]], &n2 = normals_[tri[2]];
    const Vec3 N = n0 * b0 + n1 * b1 + n2 * b2;
    const double len = N.length();
    if (!(len > 0)) return;  // the geometric normal stood in: constant, dn = 0
    const Vec3 ns = N / len;
    // d(N/|N|) = (I - ns ns^T) dN / |N|, with dN/db1 = n1 - n0 and dN/db2 = n2 - n0.
    const Vec3 d1 = n1 - n0, d2 = n2 - n0;
    const Vec3 dn1 = (d1 - ns * dot(ns, d1)) / len, dn2 = (d2 - ns * dot(ns, d2)) / len;
    const InverseChart j = inverseChart(its.primIndex);
    its.dndu = dn1 * j.j00 + dn2 * j.j10;
    its.dndv = dn1 * j.j01 + dn2 * j.j11;
}

void TriangleMesh::fillIntersection(const Ray &ray, double t, uint32_t primIndex, const Vec2 &embreeUV,
                                    Intersection &its) const {
    // Embree intersected a float copy of the triangle; redo it in double (Moeller and Trumbore 1997) so
    // that the hit lies on the exact triangle. Embree's barycentrics remain for a ray in the plane.
    const auto &tri = triangles_[primIndex];
    const Vec3 &p0 = positions_[tri[0]];
    const Vec3 e1 = positions_[tri[1]] - p0, e2 = positions_[tri[2]] - p0;
    const Vec3 pvec = cross(ray.d, e2);
    const double det = dot(e1, pvec);
    double b1 = embreeUV.x, b2 = embreeUV.y;
    if (det != 0) {
        const double inv = 1.0 / det;
        const Vec3 tvec = ray.o - p0, qvec = cross(tvec, e1);
        const double u = dot(tvec, pvec) * inv, v = dot(ray.d, qvec) * inv, tt = dot(e2, qvec) * inv;
        if (std::isfinite(u) && std::isfinite(v) && std::isfinite(tt)) {
            b1 = u;
            b2 = v;
            t = tt;
        }
    }
    its.t = t;
    fillSurface(primIndex, b1, b2, its);
}

void TriangleMesh::samplePosition(PositionSample &ps, const Vec2 &u) const {
    uint32_t prim;
    Vec2 b;
    if (parallelogram_) {
        // p + x (q - p) + y (s - p) is p (1 - x) + q (x - y) + r y in triangle 0 (x >= y), since s - p = r - q,
        // and p (1 - y) + s (y - x) + r x in triangle 1: the corners' weights, as barycentrics of each triangle.
        prim = u.x >= u.y ? 0 : 1;
        const double lo = std::min(u.x, u.y), hi = std::max(u.x, u.y);
        const double w0 = 1.0 - hi, w1 = hi - lo, w2 = lo;
        const auto &pick = parallelogram_->pick[prim];
        b = Vec2(pick[0][0] * w0 + pick[0][1] * w1 + pick[0][2] * w2,
                 pick[1][0] * w0 + pick[1][1] * w1 + pick[1][2] * w2);
    } else {
        double ux;
        prim = static_cast<uint32_t>(areaDist_.sampleDiscrete(u.x, nullptr, &ux));
        b = warp::squareToUniformTriangle(Vec2(ux, u.y));
    }
    surfacePoint(prim, b.x, b.y, ps.p, ps.n, ps.uv);  // a position needs no shading frame
    ps.pdf = invArea_;
    ps.measure = Measure::Area;
    ps.shape = this;
}

std::shared_ptr<Shape> TriangleMesh::transformedCopy(const Transform &toWorld, const Properties &where) const {
    auto copy = std::make_shared<TriangleMesh>(*this);
    copy->transformInPlace(toWorld);
    if (!withinFloatRange(copy->positions_))
        where.fail("toWorld", "the instanced mesh exceeds the single-precision range of the ray tracer");
    copy->updateSamplingData();
    return copy;
}

}  // namespace pf
