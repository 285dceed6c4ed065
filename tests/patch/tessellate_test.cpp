// Tessellation: exact vertices and normals, finite normals at collapsed edges, and
// patches that share a boundary sharing their boundary vertices (no cracks).
#include <gtest/gtest.h>

#include <map>

#include "patch/scene.h"
#include "patch/tessellate.h"

namespace patchscan {
namespace {

TEST(Tessellate, SphereVerticesAndNormalsAreExact) {
  constexpr double kExactTol = 1e-12;  // unit-sized trigonometry: rounding ~1e-15
  const Surface sphere{Sphere(2.0, -2, 2, 360), Affine3(Eigen::Translation3d(1, 2, 3))};
  for (int rate : {1, 3, 8}) {
    TessMesh m;
    TessellateUniform(sphere, rate, 7, &m);
    EXPECT_EQ(m.triangles.size(), 2u * rate * rate);
    EXPECT_EQ(m.vertices.size(), static_cast<size_t>((rate + 1) * (rate + 1)));
    for (const TessVertex& v : m.vertices) {
      const Vec3 r = v.position - Vec3(1, 2, 3);
      EXPECT_NEAR(r.norm(), 2.0, kExactTol);
      EXPECT_NEAR(v.normal.norm(), 1.0, kExactTol);
      // Parallel to the radius everywhere, the poles (collapsed edges) included.
      EXPECT_NEAR(std::abs(v.normal.dot(r / 2.0)), 1.0, 1e-6) << "uv " << v.uv.transpose();
    }
    for (std::uint32_t s : m.surfaceOf) EXPECT_EQ(s, 7u);
  }
}

TEST(Tessellate, TeapotIsCrackFree) {
  // Every patch-boundary vertex of the teapot that lies on another patch's boundary
  // coincides with a vertex of that patch: neighbours share their edge points exactly
  // (equal rates on shared edges). Counted by exact position.
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  const Scene& scene = std::get<Scene>(loaded);
  TessMesh m;
  for (size_t k = 0; k < scene.surfaces.size(); ++k)
    TessellateUniform(scene.surfaces[k], 6, static_cast<std::uint32_t>(k), &m);
  const std::size_t moved = WeldBoundaryVertices(&m, kWeldRelTol * scene.WorldBounds().Diagonal().norm());
  EXPECT_GT(moved, 0u);  // without the weld, shared edges differ in their last bits
  std::map<std::tuple<double, double, double>, int> seen;
  for (const TessVertex& v : m.vertices)
    if (v.uv.x() == 0 || v.uv.x() == 1 || v.uv.y() == 0 || v.uv.y() == 1)
      ++seen[{v.position.x(), v.position.y(), v.position.z()}];
  int lonely = 0;
  for (const auto& [p, n] : seen) lonely += n == 1;
  RecordProperty("lonely_boundary_points", lonely);
  // The teapot's open boundaries: the spout tip, the handle ends and the lid-body gap
  // are free edges; everything else is shared. At rate 6 each free patch edge has 7
  // points; measured: 80 after welding, 654 without.
  EXPECT_LE(lonely, 96) << "boundary points found on one patch only";
  for (const TessVertex& v : m.vertices) EXPECT_TRUE(v.normal.allFinite());
}

}  // namespace
}  // namespace patchscan

namespace patchscan {
namespace {

TEST(Tessellate, ScreenRatesAreEqualOnSharedEdges) {
  // Edges of two teapot patches with the same four control points (in either order) get
  // the same rate, so neighbours meet vertex to vertex.
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  const Scene& scene = std::get<Scene>(loaded);
  Camera cam = FrameBounds(scene.WorldBounds(), Camera{}, DefaultViewDirection(Vec3(0, 0, 1)));
  using EdgeKey = std::array<std::tuple<double, double, double>, 4>;
  auto key = [](const BicubicPatch& p, int e) {
    // Bfr edge order v=0, u=1, v=1, u=0, points along the edge; sorted to ignore direction.
    EdgeKey k;
    for (int m = 0; m < 4; ++m) {
      const int i = e == 1 ? 3 : e == 3 ? 0 : m, j = e == 0 ? 0 : e == 2 ? 3 : m;
      const Vec3& q = p.BezierPoints()[4 * j + i];
      k[m] = {q.x(), q.y(), q.z()};
    }
    if (k[3] < k[0]) std::reverse(k.begin(), k.end());
    return k;
  };
  for (double pixels : {2.0, 7.5, 30.0}) {
    std::map<EdgeKey, int> rateOf;
    int shared = 0;
    for (const Surface& s : scene.surfaces) {
      const auto rates = ScreenEdgeRates(s, cam, pixels);
      for (int e = 0; e < 4; ++e) {
        const auto [it, inserted] = rateOf.emplace(key(std::get<BicubicPatch>(s.shape), e), rates[e]);
        if (!inserted) {
          ++shared;
          EXPECT_EQ(it->second, rates[e]) << "pixels " << pixels;
        }
        EXPECT_GE(rates[e], 1);
      }
    }
    EXPECT_GE(shared, 40);  // the teapot's patches share most of their edges
  }
}

}  // namespace
}  // namespace patchscan
