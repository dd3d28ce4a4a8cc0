// Triangle meshes (Mitsuba 0.6's TriMesh): the common representation behind obj, ply, serialized,
// rectangle and cube. Geometry is kept in double precision in world space; Embree gets a float copy
// and every hit is recomputed in double against the double triangle (fillIntersection).
//
// Differential geometry follows pbrt-v3 §3.6.2-3.6.3: with texture coordinates, dp/du and dp/dv are the
// partials with respect to them; without (or with a degenerate texture mapping) the chart is the
// barycentric one, uv = (b1, b2), so dp/du = p1 - p0 and dp/dv = p2 - p0. Shading normals interpolate
// the vertex normals and are differentiated through the normalization; flat triangles have dn = 0.
#pragma once
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/distribution.h"
#include "core/transform.h"
#include "shape/shapegroup.h"

namespace pf {

// A mesh as read from a file, in object space.
struct MeshData {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  // empty, or one per vertex
    std::vector<Vec2> uvs;      // empty, or one per vertex
    std::vector<std::array<uint32_t, 3>> triangles;
    bool faceNormals = false;  // the file asks for a faceted look (Mitsuba serialized flag)
};

// Parameters every Mitsuba mesh plugin accepts.
struct MeshOptions {
    Transform toWorld;
    bool faceNormals = false;     // ignore/do not generate vertex normals (faceted look)
    bool flipNormals = false;     // turn every normal around
    double maxSmoothAngle = 0.0;  // degrees; > 0 discards the file's normals and rebuilds them per crease
    // toWorld, faceNormals and flipNormals (every mesh plugin).
    static MeshOptions fromProperties(const Properties &props);
    // The above and maxSmoothAngle (the plugins that read mesh files).
    static MeshOptions forMeshFile(const Properties &props);
};

class TriangleMesh final : public Shape, public Instanceable {
public:
    // Validates `data` (finite values, indices in range, at least one triangle of non-zero area) and
    // prepares it as Mitsuba does: transform to world space, drop degenerate triangles, generate
    // angle-weighted smooth normals unless faceNormals (Thuermer & Wuethrich 1998, as Mitsuba's
    // TriMesh::computeNormals), rebuild them per crease for maxSmoothAngle, apply flipNormals. Problems
    // raise SceneError naming `source` (the file, or the plugin). Reads the shape's bsdf/emitter/media
    // children from `props`.
    TriangleMesh(const Properties &props, MeshData data, const MeshOptions &opts, const std::string &source);

    unsigned addToEmbree(RTCDevice device, RTCScene scene) const override;
    void fillIntersection(const Ray &ray, double t, uint32_t primIndex, const Vec2 &embreeUV,
                          Intersection &its) const override;
    void fillNormalDerivatives(Intersection &its) const override;
    AABB bbox() const override { return bbox_; }
    double surfaceArea() const override { return area_; }
    size_t primitiveCount() const override { return triangles_.size(); }
    void samplePosition(PositionSample &ps, const Vec2 &u) const override;
    std::shared_ptr<Shape> transformedCopy(const Transform &toWorld, const Properties &where) const override;

    size_t vertexCount() const { return positions_.size(); }
    bool hasVertexNormals() const { return !normals_.empty(); }
    bool hasTexCoords() const { return !uvs_.empty(); }
    const std::vector<Vec3> &positions() const { return positions_; }
    const std::vector<Vec3> &normals() const { return normals_; }
    const std::vector<std::array<uint32_t, 3>> &triangles() const { return triangles_; }

private:
    // Validates, transforms and cleans up `data` as described at the constructor.
    void build(MeshData data, const MeshOptions &opts, const std::string &source);
    // Applies a transform to positions and normals (and the winding, for mirroring transforms).
    void transformInPlace(const Transform &toWorld);
    // Replaces the normals by per-crease smooth normals (maxSmoothAngle).
    void rebuildCreases(double maxAngleDeg);
    // Recomputes the area distribution, total area, bounding box and the per-triangle constants below.
    void updateSamplingData();
    // parallelogram_ for the present positions and triangles.
    void findParallelogram();
    // (j00 j01; j10 j11) = d(b1, b2)/d(u, v), the inverse Jacobian of triangle prim's texture chart (pbrt-v3
    // §3.6.2); the identity where the barycentric chart stands in.
    struct InverseChart {
        double j00 = 1, j01 = 0, j10 = 0, j11 = 1;
    };
    InverseChart inverseChart(uint32_t prim) const;
    // Point of triangle `prim` at barycentrics (b1, b2): position, geometric normal (on the side of the
    // vertex normals), uv; returns the interpolated vertex normal, not normalized (zero without normals).
    Vec3 surfacePoint(uint32_t prim, double b1, double b2, Vec3 &p, Vec3 &ng, Vec2 &uv) const;
    // What every hit and position sample on a triangle shares, whatever the point: its unit normal by the
    // winding (before surfacePoint orients it) and its partials dp/du, dp/dv. Kept per triangle (72 bytes)
    // instead of being recomputed at every hit, where a cross product, two square roots and two divisions
    // took about a tenth of the path tracer's time on cornell-box (issue 17's profile); the values are
    // computed by the same expressions as before, so hits are bit for bit the same.
    struct TriangleConstants {
        Vec3 ng, dpdu, dpdv;
    };
    // The full hit at barycentrics (b1, b2): surfacePoint, partials and shading frame; dn/du and dn/dv are
    // left to fillNormalDerivatives.
    void fillSurface(uint32_t prim, double b1, double b2, Intersection &its) const;

    std::vector<Vec3> positions_, normals_;
    std::vector<Vec2> uvs_;
    std::vector<std::array<uint32_t, 3>> triangles_;
    std::vector<TriangleConstants> constants_;  // per triangle
    // Flat-shaded meshes (no vertex normals, or the same normal at a triangle's three corners: rectangles,
    // cubes, faceted models) have one shading frame per triangle, kept here (72 bytes per triangle; empty
    // for meshes with any smooth triangle). A hit then skips the interpolation, normalization and
    // Gram-Schmidt of the shading normal, two square roots and two divisions in a dependent chain. With
    // equal corner normals the frame is the one hits computed before up to rounding (the interpolated
    // normal n (b0 + b1 + b2) normalized is n), so bits may differ in the last place; without vertex
    // normals it is the same expression, bit for bit.
    std::vector<Frame> flatFrames_;
    // A mesh of two triangles that form a parallelogram (every rectangle shape, a quad from a mesh file) samples
    // positions with one affine map of the unit square, as Mitsuba 0.6 samples its analytic rectangle, instead
    // of choosing a triangle by area and warping a square onto it: that choice and the warp's square root were
    // 5.6% of a `path` profile on cornell-box, whose light is a rectangle (issue 17). Corners p, q, r, s in
    // order around it, p - r the diagonal that the triangles share, q in triangle 0: u = (x, y) maps to
    // p + x (q - p) + y (s - p), in triangle 0 where x >= y. pick[t][k][c] is 1 where corner c (0: p, 1: q or s,
    // 2: r) is triangle t's vertex k + 1, else 0: its barycentrics are the corners' weights through these factors,
    // exactly (products with 1 and 0), without a branch on which half the sample fell in, which mispredicted half
    // the time, or an indexed reload of the weights.
    struct Parallelogram {
        double pick[2][2][3];
    };
    std::optional<Parallelogram> parallelogram_;
    Distribution1D areaDist_;
    AABB bbox_;
    double area_ = 0;
    double invArea_ = 0;  // 1 / area_, every position sample's density
};

// Reads the mesh file formats into MeshData; each throws SceneError naming `path` (and the line for
// text formats) for a missing, truncated or malformed file.
MeshData readOBJ(const std::string &path, bool flipTexCoords);
MeshData readPLY(const std::string &path);
MeshData readSerialized(const std::string &path, int64_t shapeIndex);

}  // namespace pf
