// NURBS pieces through the exact scan: against the ray caster sample by sample, and the
// rational NuPatch sphere against the Sphere quadric of the same size and pose, two
// different parameterisations of one surface: the same samples covered (but within
// kEdgePx of the silhouette), the same depths and the same normals.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "patch/nurbs_shapes.h"
#include "patch/surface.h"
#include "xscan/agreement.h"

namespace patchscan {
namespace {

std::vector<Surface> Pieces(const NurbsSurface& n, const Affine3& placed = Affine3::Identity()) {
  std::vector<Surface> out;
  for (NurbsPiece& p : SplitNurbs(n)) out.push_back(Surface{std::move(p), placed});
  return out;
}

// The views: oblique, the north pole face on, and the sphere seen along its seam (u = 0).
std::vector<Camera> Views() {
  return {test::View(Vec3(3.1, -4.2, 2.6), 64), test::View(Vec3(0.0, 0.0, 5.0), 64, Vec3(0, 1, 0)),
          test::View(Vec3(5.0, 0.0, -0.4), 64)};
}

TEST(NurbsScan, PiecesAgreeWithTheRayCaster) {
  for (const Camera& c : Views()) test::ExpectAgree(Pieces(test::NurbsSphere(1.0)), c, "NURBS sphere");
  Affine3 m = Affine3::Identity();
  m.scale(0.5);
  for (const Camera& c : Views()) test::ExpectAgree(Pieces(test::WavyNurbs(), m), c, "wavy NURBS");
}

struct Sample {
  double w = INFINITY;
  Vec3 normal = Vec3::Zero();
};

class NearestWithNormal final : public raster::FragmentRow {
 public:
  explicit NearestWithNormal(std::vector<Sample>* row) : row_(row) {}
  void Add(int column, const raster::Fragment& f) override {
    Sample& s = (*row_)[static_cast<std::size_t>(column)];
    if (f.w < s.w) s = {f.w, f.normal};
  }
  void AddTriangle(const raster::RasterVertex&, const raster::RasterVertex&, const raster::RasterVertex&,
                   std::uint32_t) override {
    ADD_FAILURE() << "a triangle from the exact scan";
  }

 private:
  std::vector<Sample>* row_;
};

std::vector<Sample> ScanImage(std::span<const Surface> surfaces, const Camera& camera) {
  ExactScan scan(surfaces, camera);
  const raster::SampleColumns cols{0.5, 1.0, camera.width};
  std::vector<Sample> image(static_cast<std::size_t>(camera.width * camera.height));
  for (int j = 0; j < camera.height; ++j) {
    std::vector<Sample> row(static_cast<std::size_t>(camera.width));
    NearestWithNormal out(&row);
    EXPECT_TRUE(scan.ScanRow(j + 0.5, cols, out));
    std::copy(row.begin(), row.end(), image.begin() + static_cast<std::ptrdiff_t>(j * camera.width));
  }
  EXPECT_EQ(scan.Stats()[Counter::Failures], 0);
  return image;
}

TEST(NurbsScan, TheRationalSphereIsTheSphereQuadric) {
  // Both solve to 1e-7 px or better (agreement.h): depths agree to kDepthRel and unit
  // normals, computed from each surface's own derivatives at its solved (u,v), to 1e-6.
  constexpr double kNormal = 1e-6;
  Affine3 pose = Affine3::Identity();
  pose.translate(Vec3(0.2, -0.1, 0.3)).rotate(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
  const std::vector<Surface> nurbs = Pieces(test::NurbsSphere(1.3), pose);
  const std::vector<Surface> quadric = {Surface{Sphere(1.3, -1.3, 1.3, 360.0), pose}};
  for (const Camera& camera : Views()) {
    const std::vector<Sample> a = ScanImage(nurbs, camera), b = ScanImage(quadric, camera);
    const test::RayCaster caster(quadric, camera);
    long covered = 0, nearEdge = 0;
    double worstNormal = 0.0, worstDepth = 0.0;
    for (int j = 0; j < camera.height; ++j)
      for (int i = 0; i < camera.width; ++i) {
        const Sample& x = a[static_cast<std::size_t>(j * camera.width + i)];
        const Sample& y = b[static_cast<std::size_t>(j * camera.width + i)];
        if (std::isfinite(x.w) != std::isfinite(y.w)) {
          // Only where the silhouette passes within kEdgePx of the sample.
          bool edge = false;
          for (const auto& [dx, dy] : {std::pair{test::kEdgePx, 0.0}, {-test::kEdgePx, 0.0}, {0.0, test::kEdgePx}, {0.0, -test::kEdgePx}})
            edge = edge || caster.Nearest(i + 0.5 + dx, j + 0.5 + dy).has_value() != std::isfinite(y.w);
          EXPECT_TRUE(edge) << "pixel (" << i << ", " << j << ") covered by one sphere only";
          ++nearEdge;
          continue;
        }
        if (!std::isfinite(x.w)) continue;
        ++covered;
        worstDepth = std::max(worstDepth, std::abs(x.w - y.w) / y.w);
        worstNormal = std::max(worstNormal, (x.normal - y.normal).norm());
      }
    std::cout << covered << " samples covered, " << nearEdge << " at the silhouette; worst depth " << worstDepth
              << " relative, worst normal " << worstNormal << '\n';
    EXPECT_GT(covered, 1000);
    EXPECT_LE(worstDepth, test::kDepthRel);
    EXPECT_LE(worstNormal, kNormal);
  }
}

}  // namespace
}  // namespace patchscan
