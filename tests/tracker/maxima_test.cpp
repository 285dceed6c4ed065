// The maxima pre-pass against closed forms and against brute-force sampling.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "patch/scene.h"
#include "tracker/maxima.h"

namespace patchscan {
namespace {

Camera View(const Vec3& eye, const Vec3& lookAt = Vec3::Zero()) {
  Camera c;
  c.width = 640;
  c.height = 480;
  c.eye = eye;
  c.lookAt = lookAt;
  c.up = Vec3(0, 0, 1);
  c.fovDeg = 35;
  c.hither = 0.01;
  return c;
}

// The smallest screen y over a dense grid of (u,v): a brute-force reference for the
// topmost point, accurate to the grid spacing squared times the curvature.
double BruteTopY(const Surface& s, const ScreenMap& map, Vec2* at = nullptr) {
  constexpr int kGrid = 1500;
  double best = INFINITY;
  for (int j = 0; j <= kGrid; ++j)
    for (int i = 0; i <= kGrid; ++i) {
      ScreenDerivs d;
      EvaluateScreen(s, map, double(i) / kGrid, double(j) / kGrid, DerivOrder::Position, &d);
      if (d.p.y() < best) {
        best = d.p.y();
        if (at) *at = Vec2(double(i) / kGrid, double(j) / kGrid);
      }
    }
  return best;
}

// Brute-force grid error: curvature (~1e3 px per unit^2) times (1/1500)^2 / 2, with margin.
constexpr double kBruteTolPx = 2e-3;

std::string Describe(const std::vector<Stationary>& found) {
  std::string s;
  for (const Stationary& p : found)
    s += std::string(ToString(p.kind)) + " at (" + std::to_string(p.uv.x()) + ", " +
         std::to_string(p.uv.y()) + ") y " + std::to_string(p.y) + "\n";
  return s;
}

int Count(const std::vector<Stationary>& f, StationaryKind k) {
  return static_cast<int>(std::count_if(f.begin(), f.end(), [k](const Stationary& s) { return s.kind == k; }));
}

TEST(Maxima, SphereHasOneStrictMaximumAtItsTop) {
  // Poles turned to the side so the top of the image is inside the (u,v) domain.
  Surface sphere{Sphere(1, -1, 1, 360), Affine3(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()))};
  const ScreenMap map(View(Vec3(0.5, -6, 2)), sphere.worldFromObject);
  Counters st;
  const auto found = FindStationaryPoints(sphere, map, &st);
  // Nothing else: in particular not the poles (collapsed edges) nor the seam's corners.
  ASSERT_EQ(found.size(), 1u) << Describe(found);
  ASSERT_EQ(found[0].kind, StationaryKind::StrictMaximum) << Describe(found);
  EXPECT_GT(st[Counter::MaximaRejectedCollapsed], 0);
  const double brute = BruteTopY(sphere, map);
  EXPECT_LE(found[0].y, brute + 1e-9);
  EXPECT_GE(found[0].y, brute - kBruteTolPx);
  EXPECT_GT(st[Counter::MaximaDuplicates], 0);  // many seeds climb to the same top
}

TEST(Maxima, TorusHasAMaximumAndTwoSaddles) {
  // A torus seen obliquely: its height has a maximum, a minimum and two saddles (the top
  // and bottom of the inner rim). Turned so no stationary point sits on the seam u = 0.
  Surface torus{Torus(1.5, 0.5, 0, 360, 360), Affine3(Eigen::AngleAxisd(0.4, Vec3::UnitZ()))};
  torus.worldFromObject.prerotate(Eigen::AngleAxisd(0.9, Vec3::UnitX()));
  const ScreenMap map(View(Vec3(0.3, -9, 1.0)), torus.worldFromObject);
  const auto found = FindStationaryPoints(torus, map);
  EXPECT_EQ(Count(found, StationaryKind::StrictMaximum), 1) << Describe(found);
  EXPECT_EQ(Count(found, StationaryKind::Saddle), 2) << Describe(found);
  const double brute = BruteTopY(torus, map);
  EXPECT_NEAR(found.front().y, brute, kBruteTolPx);
  for (const Stationary& s : found) {
    if (s.kind != StationaryKind::Saddle) continue;
    EXPECT_LT(s.hessH.determinant(), 0) << "saddle with a definite Hessian";
    EXPECT_LE(s.gradH.norm(), 1e-6 * s.hessH.norm());
  }
}

TEST(Maxima, SaddleSurfaceHasOneSaddle) {
  const Surface saddle{Saddle(1.0), Affine3::Identity()};
  const ScreenMap map(View(Vec3(0.2, -5, 3)), saddle.worldFromObject);
  const auto found = FindStationaryPoints(saddle, map);
  ASSERT_EQ(Count(found, StationaryKind::Saddle), 1) << Describe(found);
  // The top of the image is on the boundary: an edge or corner maximum, at the brute top.
  EXPECT_NEAR(found.front().y, BruteTopY(saddle, map), kBruteTolPx) << Describe(found);
  EXPECT_NE(found.front().kind, StationaryKind::Saddle);
}

TEST(Maxima, CylinderSideOnIsALineOfMaxima) {
  // Axis along x, parallel to the image; eye level with the axis: the top outline is a
  // horizontal line, a parabolic cylinder (§3.4), reported once.
  Surface cyl{Cylinder(1, -2, 2, 360), Affine3(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()))};
  cyl.worldFromObject.prerotate(Eigen::AngleAxisd(0.3, Vec3::UnitX()));  // seam off the top
  const ScreenMap map(View(Vec3(0, -8, 0)), cyl.worldFromObject);
  const auto found = FindStationaryPoints(cyl, map);
  const int lines = Count(found, StationaryKind::LineOfMaxima);
  const int edges = Count(found, StationaryKind::EdgeMaximum);
  EXPECT_GE(lines + edges, 1) << Describe(found);
  EXPECT_EQ(Count(found, StationaryKind::StrictMaximum), 0) << Describe(found);
  EXPECT_NEAR(found.front().y, BruteTopY(cyl, map), kBruteTolPx) << Describe(found);
}

TEST(Maxima, TeapotTopOfEveryPatchIsFoundAndApexesAreNotMaxima) {
  // Differential: for every teapot patch, the topmost point by dense sampling is one of
  // the reported maxima (to the grid's accuracy); every reported strict maximum is
  // higher than its neighbourhood.
  auto loaded = LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt");
  const Scene& scene = std::get<Scene>(loaded);
  const Camera cam = FrameBounds(scene.WorldBounds(), View(Vec3::Zero(), Vec3(1, 0, 0)),
                                 DefaultViewDirection(Vec3(0, 0, 1)));
  Counters st;
  for (size_t k = 0; k < scene.surfaces.size(); ++k) {
    const Surface& s = scene.surfaces[k];
    const ScreenMap map(cam, s.worldFromObject);
    const auto found = FindStationaryPoints(s, map, &st);
    ASSERT_FALSE(found.empty()) << "patch " << k + 1;
    Vec2 at;
    const double brute = BruteTopY(s, map, &at);
    EXPECT_NEAR(found.front().y, brute, kBruteTolPx) << "patch " << k + 1 << "\n" << Describe(found);
    for (const Stationary& m : found) {
      if (m.kind != StationaryKind::StrictMaximum) continue;
      for (double du : {-1e-3, 0.0, 1e-3})
        for (double dv : {-1e-3, 0.0, 1e-3}) {
          ScreenDerivs d;
          const Vec2 q = (m.uv + Vec2(du, dv)).cwiseMax(0.0).cwiseMin(1.0);
          EvaluateScreen(s, map, q.x(), q.y(), DerivOrder::Position, &d);
          EXPECT_GE(d.p.y(), m.y - 1e-9) << "patch " << k + 1;
        }
    }
  }
  EXPECT_GT(st[Counter::MaximaRejectedCollapsed], 0);  // climbs stopped at the lid apex or bottom centre
}

}  // namespace
}  // namespace patchscan
