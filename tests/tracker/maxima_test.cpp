// The maxima pre-pass against closed forms and against brute-force sampling.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "patch/cages.h"
#include "scene/scene.h"
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


TEST(Maxima, EdgeMaximaAreStationaryAlongTheirEdgesAndAProvenCornerIsTheSearchs) {
  // An edge maximum's remaining Newton step along its edge, |h_t| / max(|h_tt|, 1), in
  // parameter units: a climb stops on a gain below 1e-10 px, so h_t^2 / (2 |h_tt|) < 1e-10
  // and the step is below 1.4e-5 (measured: 5.7e-8; 0.106 when a climb cut short by the
  // boundary stopped there).
  constexpr double kEdgeStationaryParam = 1e-4;
  // Where y is proven monotone in u and v (the Bernstein coefficients of y_u's and y_v's
  // numerators all of one sign), FindStationaryPoints returns the top corner without
  // climbing. It must be exactly what the climbs find: one corner maximum, its (u, v), y,
  // gradient and Hessian bit for bit (each climb ends clamped to the corner and evaluates
  // it there). Over the teapot's patches from three views and every Catmull-Clark test
  // cage's faces (held, so fitted as bicubic pieces where they are) from two.
  int surfaces = 0, proven = 0;
  double worstAlong = 0.0;  // |h along the edge| / max(|its second derivative|, 1) at an edge maximum
  const auto check = [&](const Surface& s, const ScreenMap& map, const std::string& what) {
    Counters counters;
    const std::vector<Stationary> fast = FindStationaryPoints(s, map, &counters);
    if (what == "teapot patch 21") setenv("PTRACE", "1", 1);
    const std::vector<Stationary> full = SearchStationaryPoints(s, map);
    unsetenv("PTRACE");
    ++surfaces;
    // Every edge maximum the search reports is one along its edge: y's derivative along
    // the edge vanishes there (Newton's or the climb's tolerance), which a climb left an
    // ulp inside the domain (before its step was set on the boundary) broke.
    for (const Stationary& p : full) {
      if (p.kind != StationaryKind::EdgeMaximum) continue;
      const int along = p.edge == static_cast<int>(PatchEdge::U0) || p.edge == static_cast<int>(PatchEdge::U1) ? 1 : 0;
      worstAlong = std::max(worstAlong, std::abs(p.gradH[along]) / std::max(std::abs(p.hessH(along, along)), 1.0));
    }
    if (counters[Counter::MaximaProvenMonotone] == 0) return;
    ++proven;
    ASSERT_EQ(full.size(), 1u) << what << "\n" << Describe(full);
    ASSERT_EQ(fast.size(), 1u) << what;
    EXPECT_EQ(full[0].kind, StationaryKind::CornerMaximum) << what;
    EXPECT_EQ(fast[0].kind, full[0].kind) << what;
    EXPECT_EQ(fast[0].uv, full[0].uv) << what;
    EXPECT_EQ(fast[0].y, full[0].y) << what;
    EXPECT_EQ(fast[0].gradH, full[0].gradH) << what;
    EXPECT_EQ(fast[0].hessH, full[0].hessH) << what;
  };
  const Scene teapot = std::get<Scene>(LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt"));
  for (const Vec3& eye : {Vec3(6, -8, 5), Vec3(-7, 2, 1.5), Vec3(0.4, -0.6, 10)})
    for (std::size_t k = 0; k < teapot.surfaces.size(); ++k) {
      const Surface& s = teapot.surfaces[k];
      check(s, ScreenMap(View(eye, Vec3(0, 0, 1.5)), s.worldFromObject), "teapot patch " + std::to_string(k));
    }
  for (const test::Cage& c : test::Cages()) {
    if (c.mesh.scheme != SubdivScheme::CatmullClark) continue;
    for (SubdivFace& f : PrepareSubdivFaces(c.mesh)) {
      f.Hold(/*fit=*/true);  // as a scan does
      const std::string what = c.name + ", " + f.Describe();
      const Surface s{f, Affine3::Identity()};
      for (const Vec3& eye : {Vec3(3.1, -4.2, 2.6), Vec3(-0.7, 1.3, -5.0)}) check(s, ScreenMap(View(eye), s.worldFromObject), what);
      f.Release();
    }
  }
  std::cout << proven << " of " << surfaces << " surface views proven monotone; edge maxima at most " << worstAlong
            << " (parameter units) from stationary along their edges\n";
  EXPECT_LT(worstAlong, kEdgeStationaryParam);
  EXPECT_GT(proven, 0);
  EXPECT_LT(proven, surfaces);
}

}  // namespace
}  // namespace patchscan
