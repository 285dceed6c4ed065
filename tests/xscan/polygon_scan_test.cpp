// Polygons in a direct render (xscan/polygon_feed.h) against an independent path to the
// same surface: a planar quadrilateral given as a Polygon and as a bilinear Patch, whose
// samples the exact scan finds by Newton iteration. Both are exact, so coverage, depth
// and normal agree to rounding; and mixed with surfaces, the polygons of polygons.rib
// cover what they should in front of and behind them.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <variant>

#include "scene/rib/reader.h"
#include "xscan/exact_scan.h"
#include "xscan/polygon_feed.h"
#include "xscan/render_settings.h"

namespace patchscan {
namespace {

// Depth (relative) and unit normals (1 - |cos|) of the two renders where both cover a
// pixel fully: two exact methods (Newton to 1e-7 px in the exact scan; the plane's 1/w
// interpolated in the back end) agree far below the rounding of the float channels they
// are written to (6e-8 relative), so this is the channels' own bound with some margin.
constexpr double kChannelRelTol = 1e-6;
// With l x l samples a pixel's depth is that of its samples' centroid: the average of
// the samples' depths (exact) or the plane's depth there (triangles). Under perspective
// depth is not affine on the screen (1/w is), and the two differ by its curvature across
// a pixel: up to 2e-4 relative on this quadrilateral seen at a grazing angle.
constexpr double kCentroidDepthRelTol = 1e-3;
// Their colours: a pixel's shading call is made at its samples' centroid, from the
// samples' surface points averaged (exact) or the plane interpolated there (triangles);
// under perspective the two points differ by the plane's curvature of 1/w across a pixel.
constexpr double kColourTol = 1e-4;

Scene Read(const std::string& world) {
  auto r = ParseRib("WorldBegin\n" + world + "\nWorldEnd\n", "t.rib");
  EXPECT_TRUE(std::holds_alternative<Scene>(r)) << std::get<SourceError>(r).What();
  return std::holds_alternative<Scene>(r) ? std::get<Scene>(std::move(r)) : Scene{};
}

test::KeepRows Render(const Scene& scene, const Camera& camera, int aa) {
  raster::TriangleMesh polygons = render::PolygonTriangles(scene, camera);
  ExactScan scan(scene.surfaces, camera, ExactScanOptions{});
  PolygonFeed fed(scan, std::move(polygons));
  test::KeepRows rows(camera.width);
  EXPECT_TRUE(raster::RenderFragments(fed, test::SettingsFor(camera, aa), rows));
  return rows;
}

TEST(PolygonScan, AQuadrilateralIsItsBilinearPatch) {
  // A planar quadrilateral, not a parallelogram, tilted to the view.
  const char* p00 = "-1.3 -0.9 0.2 ", *p10 = "1.1 -1.2 -0.1 ", *p01 = "-0.8 1.0 0.3 ";
  // p11 on the plane through the other three: p00 + a (p10 - p00) + b (p01 - p00), a = 1.2, b = 0.9.
  const Vec3 a(-1.3, -0.9, 0.2), b(1.1, -1.2, -0.1), c(-0.8, 1.0, 0.3);
  const Vec3 d = a + 1.2 * (b - a) + 0.9 * (c - a);
  std::ostringstream p11;
  p11.precision(17);
  p11 << d.x() << ' ' << d.y() << ' ' << d.z();
  const Scene patch = Read(std::string("Patch \"bilinear\" \"P\" [") + p00 + p10 + p01 + p11.str() + "]");
  const Scene polygon = Read(std::string("Polygon \"P\" [") + p00 + p10 + p11.str() + " " + p01 + "]");
  ASSERT_EQ(patch.surfaces.size(), 1u);
  ASSERT_EQ(polygon.polygons.size(), 1u);
  for (const Vec3& eye : {Vec3(0.5, -4.0, 3.0), Vec3(-3.0, 2.0, 1.5)}) {
    Camera camera;
    camera.width = 160;
    camera.height = 120;
    camera.eye = eye;
    camera.lookAt = Vec3(0, 0, 0);
    camera.up = Vec3(0, 0, 1);
    camera.fovDeg = 40;
    camera.hither = 1e-3;
    for (const int aa : {1, 3}) {
      const test::KeepRows want = Render(patch, camera, aa), got = Render(polygon, camera, aa);
      int covered = 0, coverageDiffers = 0;
      double depth = 0.0, normal = 0.0, colour = 0.0;
      for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
          const float aw = want.At(x, y, 3), ag = got.At(x, y, 3);
          if (aw != ag) ++coverageDiffers;
          if (aw != 1.0f || ag != 1.0f) continue;
          ++covered;
          const double zw = want.At(x, y, raster::kChannelZ), zg = got.At(x, y, raster::kChannelZ);
          depth = std::max(depth, std::abs(zw - zg) / zw);
          const Vec3 nw(want.At(x, y, raster::kChannelN), want.At(x, y, raster::kChannelN + 1),
                        want.At(x, y, raster::kChannelN + 2));
          const Vec3 ng(got.At(x, y, raster::kChannelN), got.At(x, y, raster::kChannelN + 1),
                        got.At(x, y, raster::kChannelN + 2));
          normal = std::max(normal, 1.0 - std::abs(nw.dot(ng)));
          for (int k = 0; k < 3; ++k) colour = std::max(colour, static_cast<double>(std::abs(want.At(x, y, k) - got.At(x, y, k))));
        }
      EXPECT_GT(covered, 1000) << "aa " << aa;
      EXPECT_EQ(coverageDiffers, 0) << "aa " << aa;
      EXPECT_LT(depth, aa == 1 ? kChannelRelTol : kCentroidDepthRelTol) << "aa " << aa << ", eye " << eye.transpose();
      EXPECT_LT(normal, kChannelRelTol) << "aa " << aa;
      EXPECT_LT(colour, kColourTol) << "aa " << aa;
    }
  }
}

}  // namespace
}  // namespace patchscan
