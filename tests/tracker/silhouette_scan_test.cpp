// Silhouette trackers against a many-start solve of (y = yScan, J = 0) on every scan line.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <iostream>

#include "tracker/silhouette_scan.h"

namespace patchscan {
namespace {

Camera View(const Vec3& eye) {
  Camera c;
  c.width = 128;
  c.height = 96;
  c.eye = eye;
  c.lookAt = Vec3::Zero();
  c.up = Vec3(0, 0, 1);
  c.fovDeg = 40;
  c.hither = 0.01;
  return c;
}

// Whether uv is on a collapsed edge (a pole, the lid apex), where J vanishes identically:
// brute-force solutions there are not silhouette crossings.
bool OnCollapsedEdge(const Surface& s, const ScreenMap& map, const Vec2& p) {
  ScreenDerivs d;
  EvaluateScreen(s, map, p.x(), p.y(), DerivOrder::First, &d);
  return d.dpdu.head<2>().norm() < 1e-6 * d.dpdv.head<2>().norm() ||
         d.dpdv.head<2>().norm() < 1e-6 * d.dpdu.head<2>().norm();
}

// The many-start solve's crossings of line y, without points on a collapsed edge.
std::vector<Vec2> ManyStartCrossings(const Surface& s, const ScreenMap& map, double y, int grid = 48) {
  std::vector<Vec2> want = SilhouetteCrossingsBruteForce(s, map, y, grid);
  std::erase_if(want, [&](const Vec2& p) { return OnCollapsedEdge(s, map, p); });
  return want;
}

// A torus turned so that its view has saddles and an inner silhouette.
Surface TurnedTorus() {
  Surface torus{Torus(1.5, 0.5, 0, 360, 360), Affine3(Eigen::AngleAxisd(0.4, Vec3::UnitZ()))};
  torus.worldFromObject.prerotate(Eigen::AngleAxisd(0.9, Vec3::UnitX()));
  return torus;
}

// Tracked and brute-force crossings agree, scan line by scan line, to kMatchUv.
// Brute-force points on a collapsed edge (a pole, where J vanishes identically) are not
// silhouette crossings and are left out.
constexpr double kMatchUv = 1e-6;

void ExpectTracksMatch(const Surface& s, const Camera& cam, const char* name,
                       Counters* statsOut = nullptr) {
  const ScreenMap map(cam, s.worldFromObject);
  Counters counters;
  EdgeScan edges(s, map, counters);
  SilhouetteScan sil(s, map, FindStationaryPoints(s, map), counters);
  long compared = 0;
  for (int row = 0; row < cam.height; ++row) {
    const double y = row + 0.5;
    edges.Advance(y);
    sil.Advance(y, edges);
    const std::vector<Vec2> want = ManyStartCrossings(s, map, y);
    ASSERT_EQ(sil.Trackers().size(), want.size()) << name << " scan line y " << y;
    for (const SilhouetteTracker& t : sil.Trackers()) {
      double best = INFINITY;
      for (const Vec2& w : want) best = std::min(best, (w - t.uv).norm());
      EXPECT_LE(best, kMatchUv) << name << " y " << y << " tracker at " << t.uv.transpose();
      ++compared;
    }
  }
  EXPECT_GT(compared, 50) << name;
  if (statsOut) *statsOut = counters;
}

TEST(SilhouetteScan, SphereBornAtItsMaximumAndThroughTheSeam) {
  // Poles to the side: the silhouette circle starts at the top (a strict maximum) and
  // crosses the seam u = 0 / u = 1, where folds on the edge trackers create trackers.
  Surface sphere{Sphere(1, -1, 1, 360), Affine3(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()))};
  sphere.worldFromObject.prerotate(Eigen::AngleAxisd(0.35, Vec3::UnitZ()));
  Counters st;
  ExpectTracksMatch(sphere, View(Vec3(0.5, -5, 1.5)), "sphere", &st);
  EXPECT_EQ(st[Counter::SilhouettesBornAtMaxima], 2);
  EXPECT_GT(st[Counter::SilhouettesBornAtFolds], 0);
  EXPECT_GT(st[Counter::SilhouettesLeft] + st[Counter::SilhouettesDied], 0);
}

TEST(SilhouetteScan, TorusWithSaddlesAndAnInnerSilhouette) {
  const Surface torus = TurnedTorus();
  Counters st;
  ExpectTracksMatch(torus, View(Vec3(0.3, -9, 1.0)), "torus", &st);
  EXPECT_GT(st[Counter::SilhouettesBornAtSaddles], 0);
  EXPECT_EQ(st[Counter::SilhouettesBornAtMaxima], 2);
}

TEST(SilhouetteScan, ACurveLeavingAcrossAnEdgeNeedsNoSearch) {
  // A tilted cylinder: its two silhouette rulings enter across one end (folds: trackers
  // born there) and leave across the other, where J changes sign on that end's edge
  // trackers too. A fold where a tracker left across the same edge is explained: no
  // subdivision search runs (one did for every exit, the most costly step of the scan).
  Surface cylinder{Cylinder(1, -1, 1, 360), Affine3(Eigen::AngleAxisd(0.6, Vec3::UnitX()))};
  cylinder.worldFromObject.prerotate(Eigen::AngleAxisd(0.35, Vec3::UnitZ()));
  Counters st;
  ExpectTracksMatch(cylinder, View(Vec3(0.5, -6, 1.0)), "cylinder", &st);
  EXPECT_GE(st[Counter::SilhouettesBornAtFolds], 2);
  EXPECT_GE(st[Counter::SilhouettesDied], 2);
  EXPECT_EQ(st[Counter::RepairSearches], 0);
}

TEST(SilhouetteScan, TrackersMeetingAtTheCurvesLowestPointAreSearchedAroundOnly) {
  // A sphere's silhouette circle ends at its lowest point, where its two trackers run
  // into each other and both fail (Blinn 1978 §3.2.3's minimum). A pair failing together
  // is searched for lost crossings in the square around it, not over the whole domain (as
  // every death inside the domain was); the tracks still match the many-start solve on
  // every line.
  for (const double turn : {0.0, 0.35, 1.1}) {
    Surface sphere{Sphere(1, -1, 1, 360), Affine3(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()))};
    sphere.worldFromObject.prerotate(Eigen::AngleAxisd(turn, Vec3::UnitZ()));
    Counters st;
    ExpectTracksMatch(sphere, View(Vec3(0.5, -5, 1.5)), "sphere", &st);
    EXPECT_EQ(st[Counter::MinimumSearches], 1) << "turned " << turn;
    EXPECT_EQ(st[Counter::RepairSearches], 0) << "turned " << turn;
  }
}

TEST(SilhouetteScan, RepairSearchFindsWhatManyStartsFind) {
  // The subdivision search of the repairs against the many-start solve, row by row: over
  // the whole domain, and over squares of two sizes (as searched around two trackers that
  // met; not aligned with the whole domain's cells) placed off each crossing.
  const Surface torus = TurnedTorus();
  const Camera cam = View(Vec3(0.3, -9, 1.0));
  const ScreenMap map(cam, torus.worldFromObject);
  long compared = 0;
  auto nearest = [](const std::vector<Vec2>& points, const Vec2& p) {
    double best = INFINITY;
    for (const Vec2& q : points) best = std::min(best, (q - p).norm());
    return best;
  };
  for (int row = 0; row < cam.height; ++row) {
    const double y = row + 0.5;
    const std::vector<Vec2> want = ManyStartCrossings(torus, map, y);
    const std::vector<Vec2> got = SilhouetteCrossingsBySubdivision(torus, map, y);
    ASSERT_EQ(got.size(), want.size()) << "y " << y;
    for (const Vec2& g : got) {
      EXPECT_LE(nearest(want, g), kMatchUv) << "y " << y;
      ++compared;
    }
    for (const Vec2& w : want)
      for (const double side : {0.05, 0.3}) {
        const Vec2 corner = (w - Vec2(0.37, 0.61) * side).cwiseMax(0.0).cwiseMin(1.0 - side);
        EXPECT_LE(nearest(SilhouetteCrossingsBySubdivision(torus, map, y, corner.x(), corner.y(), side), w), kMatchUv)
            << "y " << y << " crossing at " << w.transpose() << " square of side " << side;
      }
  }
  EXPECT_GT(compared, 100);
}

}  // namespace
}  // namespace patchscan

#include "scene/scene.h"

namespace patchscan {
namespace {

Scene Teapot() { return std::get<Scene>(LoadScene(PATCHSCAN_SURFACES_DIR "/teapot.bpt")); }

// The teapot framed as render frames it by default, at width x height.
Camera TeapotCamera(const Scene& teapot, int width, int height) {
  Camera base;
  base.width = width;
  base.height = height;
  return FrameBounds(teapot.WorldBounds(), base, DefaultViewDirection(Vec3(0, 0, 1)));
}

TEST(SilhouetteScan, TeapotAgreesWithBruteForceOnNearlyEveryScanLine) {
  // Known gap of the Y scan alone: a silhouette that enters through an edge and runs far
  // inside within one scan line can be missed for a line or two. (In a render the X
  // scan's walk along the level curve finds such a crossing and the Y scan adopts it:
  // tests/xscan.) Measured: 1 of 3072 (patch, scan line) pairs at 128 x 96; the bound
  // below allows 3 and fails on any regression beyond.
  constexpr int kAllowedMismatches = 3;
  const Scene scene = Teapot();
  const Camera cam = TeapotCamera(scene, 128, 96);
  int mismatches = 0;
  for (size_t k = 0; k < scene.surfaces.size(); ++k) {
    const Surface& s = scene.surfaces[k];
    const ScreenMap map(cam, s.worldFromObject);
    Counters counters;
    EdgeScan edges(s, map, counters);
    SilhouetteScan sil(s, map, FindStationaryPoints(s, map), counters);
    for (int row = 0; row < cam.height; ++row) {
      const double y = row + 0.5;
      edges.Advance(y);
      sil.Advance(y, edges);
      const auto want = ManyStartCrossings(s, map, y, 32);
      bool same = want.size() == sil.Trackers().size();
      for (const SilhouetteTracker& t : sil.Trackers()) {
        double best = INFINITY;
        for (const Vec2& w : want) best = std::min(best, (w - t.uv).norm());
        same = same && best <= kMatchUv;
      }
      if (!same) {
        ++mismatches;
        std::cerr << "patch " << k + 1 << " y " << y << ": tracked " << sil.Trackers().size()
                  << ", brute force " << want.size() << "\n";
      }
    }
  }
  EXPECT_LE(mismatches, kAllowedMismatches);
}

TEST(SilhouetteScan, RepairSearchFindsEveryTeapotCrossingManyStartsFind) {
  // The search's cells are cut where neither the scan line nor the silhouette (J = 0) can
  // pass; a cut too eager would lose crossings. At 512 x 384, on every 8th scan line of
  // every patch, each crossing the many-start solve finds must be among the search's
  // (the search may find more: its starts are finer than the 24 x 24 grid's).
  const Scene scene = Teapot();
  const Camera cam = TeapotCamera(scene, 512, 384);
  long compared = 0;
  for (const Surface& s : scene.surfaces) {
    const ScreenMap map(cam, s.worldFromObject);
    for (int row = 0; row < cam.height; row += 8) {
      const double y = row + 0.5;
      const std::vector<Vec2> want = ManyStartCrossings(s, map, y, 24);
      const std::vector<Vec2> got = SilhouetteCrossingsBySubdivision(s, map, y);
      for (const Vec2& w : want) {
        double best = INFINITY;
        for (const Vec2& g : got) best = std::min(best, (w - g).norm());
        EXPECT_LE(best, kMatchUv) << "y " << y << " crossing at " << w.transpose();
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 100);
}

}  // namespace
}  // namespace patchscan
