// Trimmed NURBS through the scans: the exact scan of a square trimmed by a circle against
// the analytic answer; trimmed surfaces (loops across pieces, nested and separate loops, a
// loop along the patch's boundary and one touching it, a column on a boundary a loop runs along, a trimmed sphere) against the ray
// caster sample by sample; θ rows against the same reference; tess mode near the trim.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "patch/nurbs_shapes.h"
#include "patch/surface.h"
#include "patch/tessellate.h"
#include "xscan/agreement.h"

namespace patchscan {
namespace {

using test::TrimCircle;
using test::TrimPolygon;

std::vector<Surface> Trimmed(const NurbsSurface& n, const std::vector<std::vector<TrimCurveInput>>& loops, bool keepInside,
                             const Affine3& placed = Affine3::Identity()) {
  std::vector<Surface> out;
  for (TrimmedPiece& p : TrimPieces(std::make_shared<const TrimLoops>(loops, keepInside), SplitNurbs(n)))
    out.push_back(Surface{std::move(p.piece), placed, std::move(p.trim)});
  return out;
}

// Which samples of a 1-sample-per-pixel image a scan with `options` covers.
std::vector<char> Coverage(std::span<const Surface> surfaces, const Camera& camera, ExactScanOptions options) {
  struct Row final : raster::FragmentRow {
    std::vector<char>* covered;
    int row, width;
    void Add(int column, const raster::Fragment&) override { (*covered)[static_cast<std::size_t>(row * width + column)] = 1; }
    void AddTriangle(const raster::RasterVertex&, const raster::RasterVertex&, const raster::RasterVertex&,
                     std::uint32_t) override {
      ADD_FAILURE() << "a slab triangle";
    }
  };
  ExactScan scan(surfaces, camera, options);
  std::vector<char> covered(static_cast<std::size_t>(camera.width * camera.height), 0);
  Row out;
  out.covered = &covered;
  out.width = camera.width;
  const raster::SampleColumns cols{0.5, 1.0, camera.width};
  for (int j = 0; j < camera.height; ++j) {
    out.row = j;
    EXPECT_TRUE(scan.ScanRow(0.5 + j, cols, out));
  }
  EXPECT_EQ(scan.Stats()[Counter::Failures], 0);
  return covered;
}

// Samples where `covered` and want(x, y) differ, except within kEdgePx of a place where
// want changes.
template <class Want>
long Mismatches(const std::vector<char>& covered, const Camera& camera, Want&& want, long* wanted) {
  long wrong = 0;
  *wanted = 0;
  for (int j = 0; j < camera.height; ++j)
    for (int i = 0; i < camera.width; ++i) {
      const double x = 0.5 + i, y = 0.5 + j;
      const bool w = want(x, y);
      *wanted += w;
      if (w == (covered[static_cast<std::size_t>(j * camera.width + i)] != 0)) continue;
      bool nearEdge = false;
      for (const auto& [dx, dy] : {std::pair{test::kEdgePx, 0.0}, {-test::kEdgePx, 0.0}, {0.0, test::kEdgePx}, {0.0, -test::kEdgePx}})
        nearEdge = nearEdge || want(x + dx, y + dy) != w;
      if (!nearEdge && ++wrong <= 5) ADD_FAILURE() << "sample (" << x << ", " << y << "): want " << w;
    }
  return wrong;
}

TEST(TrimScan, SquareTrimmedByACircleMatchesTheAnalyticAnswer) {
  // The square's (u,v) at a sample from the untrimmed square (Newton on a plane), then the
  // circle's equation: nothing of the trim code in the reference.
  const Vec2 c(0.45, 0.55);
  const double r = 0.3;
  const std::vector<Surface> whole = Trimmed(test::FlatSquare(1), {}, false);  // no loops: nothing is inside
  for (const Camera& camera : {test::View(Vec3(0.4, -0.5, 3.5), 96, Vec3(0, 1, 0)), test::View(Vec3(2.5, -1.5, 1.2), 96)}) {
    const test::RayCaster caster(whole, camera);
    for (const bool keepInside : {true, false}) {
      const std::vector<Surface> trimmed = Trimmed(test::FlatSquare(1), {{TrimCircle(c, r)}}, keepInside);
      ASSERT_EQ(trimmed.size(), 1u);
      long wanted = 0;
      for (const int theta : {0, 32}) {
        const long wrong = Mismatches(Coverage(trimmed, camera, {true, theta, 0}), camera, [&](double x, double y) {
          const auto hit = caster.Nearest(x, y);
          return hit && (((hit->uv - c).norm() < r) == keepInside);
        }, &wanted);
        EXPECT_EQ(wrong, 0) << (keepInside ? "disc" : "hole") << (theta ? ", theta" : ", exact");
      }
      EXPECT_GT(wanted, 500);
    }
  }
}

// Tess mode keeps a trimmed piece's whole triangles whose centroid the trim keeps: none may
// reach further outside the disc than a triangle of the fine grid does. A flat square's
// edges, of rate 1, were once stitched to the grid in slivers that ran along the whole
// square and drew its outline round the disc. The disc touches the square's four sides, as
// a CAD face's trim touches the box of (u,v) it is given.
TEST(TrimScan, TessOfASquareTrimmedToADiscStaysNearTheDisc) {
  // The grid's triangles are about kTrimTessPx on the screen: 96 px across the square of
  // side 1 in (u,v) here, so a few pixels is a few hundredths of (u,v).
  constexpr double kOutsideUv = 0.05;
  const Vec2 c(0.5, 0.5);
  const double r = 0.5;
  const std::vector<Surface> trimmed = Trimmed(test::FlatSquare(1), {{TrimCircle(c, r)}}, true);
  for (const Camera& camera : {test::View(Vec3(0.4, -0.5, 3.5), 96, Vec3(0, 1, 0)), test::View(Vec3(2.5, -1.5, 1.2), 96)}) {
    TessMesh m;
    TessellateToChordError(trimmed[0], camera, kDefaultChordErrorPx, 0, &m);
    ASSERT_FALSE(m.triangles.empty());
    double area = 0.0, farthest = 0.0;
    for (const auto& t : m.triangles) {
      const Vec2 a = m.vertices[t[0]].uv, b = m.vertices[t[1]].uv, d = m.vertices[t[2]].uv;
      area += 0.5 * std::abs((b - a).x() * (d - a).y() - (b - a).y() * (d - a).x());
      for (const Vec2& q : {a, b, d}) farthest = std::max(farthest, (q - c).norm());
    }
    EXPECT_LT(farthest, r + kOutsideUv);
    EXPECT_NEAR(area, std::numbers::pi * r * r, 2.0 * std::numbers::pi * r * kOutsideUv);
  }
}

// A trim loop along the patch's boundary ends each walk where the boundary does: a sample
// column lying on the boundary (the square's side x = 1 in the plane through the eye and
// the image's centre column) is kept as the untrimmed boundary keeps it. It was once cut
// where a walk ended there, the loop's crossing lying a rounding before the column.
TEST(TrimScan, ALoopAlongTheBoundaryKeepsAColumnOnIt) {
  const std::vector<Vec2> boundary = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  const TrimCurveInput hole = TrimCircle(Vec2(0.5, 0.5), 0.2, true);
  // The same region twice: inside the boundary's loop and outside the hole, and outside the
  // hole alone (the domain's own boundary).
  const std::vector<Surface> looped = Trimmed(test::FlatSquare(1), {{TrimPolygon(boundary)}, {hole}}, true);
  const std::vector<Surface> holed = Trimmed(test::FlatSquare(1), {{hole}}, false);
  ASSERT_EQ(looped.size(), 1u);
  ASSERT_TRUE(looped[0].trim);
  for (const Vec3& eye : {Vec3(1.0, -2.0, 3.0), Vec3(1.0, -0.7, 1.7)}) {
    Camera camera = test::View(eye, 95);  // odd: column 47 is the centre
    camera.lookAt = Vec3(1.0, 0.0, 0.0);
    for (const int theta : {0, 32}) {
      const std::vector<char> a = Coverage(looped, camera, {true, theta, 0}), b = Coverage(holed, camera, {true, theta, 0});
      long onSide = 0, differ = 0;
      for (int j = 0; j < camera.height; ++j) {
        const std::size_t k = static_cast<std::size_t>(j * camera.width + 47);
        onSide += b[k];
        differ += a[k] != b[k];
      }
      EXPECT_GT(onSide, 10) << "theta " << theta << ": the view does not put the side on a column";
      EXPECT_EQ(differ, 0) << "theta " << theta << ", eye " << eye.transpose();
      EXPECT_TRUE(a == b) << "theta " << theta << ", eye " << eye.transpose();
    }
  }
}

// The loops of the agreement tests, on a square of 3 x 3 pieces.
struct Case {
  const char* name;
  std::vector<std::vector<TrimCurveInput>> loops;
  bool keepInside;
};
std::vector<Case> Cases() {
  const std::vector<Vec2> boundary = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  return {
      {"nested and separate loops across pieces",
       {{TrimPolygon({{0.1, 0.1}, {0.7, 0.1}, {0.7, 0.9}, {0.1, 0.9}})}, {TrimCircle(Vec2(0.4, 0.5), 0.2, true)},
        {TrimPolygon({{0.35, 0.45}, {0.45, 0.45}, {0.45, 0.55}, {0.35, 0.55}})},
        {TrimPolygon({{0.75, 0.2}, {1.0, 0.5}, {0.75, 0.8}})}},
       true},
      // An exporter's loop along the whole boundary, with holes: one touching the boundary.
      {"a loop along the boundary, a hole touching it",
       {{TrimPolygon(boundary)}, {TrimCircle(Vec2(0.5, 0.5), 0.2, true)},
        {TrimPolygon({{0.2, 0.0}, {0.2, 0.15}, {0.6, 0.15}, {0.6, 0.0}})}},
       true},
      {"a circle crossing the boundary, cut away", {{TrimCircle(Vec2(0.9, 0.3), 0.35)}}, false},
  };
}

std::vector<Camera> Views() {
  return {test::View(Vec3(0.3, -0.4, 3.6), 72, Vec3(0, 1, 0)), test::View(Vec3(2.6, -2.0, 1.4), 72),
          test::View(Vec3(-0.2, -3.4, 0.35), 72)};
}

TEST(TrimScan, TrimmedSquaresAgreeWithTheRayCaster) {
  for (const Case& k : Cases()) {
    const std::vector<Surface> s = Trimmed(test::FlatSquare(3), k.loops, k.keepInside);
    for (const Camera& c : Views()) test::ExpectAgree(s, c, k.name);
  }
}

TEST(TrimScan, TrimmedSphereAgreesWithTheRayCaster) {
  // Circles in (u,v) across the sphere's knot lines and its seam: curved trim edges on a
  // curved surface, silhouettes crossing them.
  const std::vector<Surface> s = Trimmed(test::NurbsSphere(1.0),
                                         {{TrimCircle(Vec2(0.5, 0.5), 0.2)}, {TrimCircle(Vec2(0.05, 0.35), 0.12)},
                                          {TrimPolygon({{0.2, 0.6}, {0.35, 0.9}, {0.1, 0.8}})},
                                          // The cap about the north pole, the loop around it outside the domain.
                                          {TrimPolygon({{-0.1, 0.84}, {1.1, 0.84}, {1.1, 1.1}, {-0.1, 1.1}})}},
                                         false);
  for (const Camera& c : {test::View(Vec3(3.1, -4.2, 2.6), 72), test::View(Vec3(-5.0, 0.3, 0.4), 72),
                          test::View(Vec3(4.0, 2.0, -3.0), 72), test::View(Vec3(0.5, -3.0, 3.8), 72)})
    test::ExpectAgree(s, c, "trimmed sphere");
}

TEST(TrimScan, ThetaRowsCoverWhatTheRayCasterSees) {
  for (const Case& k : Cases()) {
    const std::vector<Surface> s = Trimmed(test::FlatSquare(3), k.loops, k.keepInside);
    for (const Camera& c : Views()) {
      const test::RayCaster caster(s, c);
      auto want = [&](double x, double y) { return caster.Nearest(x, y).has_value(); };
      long wanted = 0;
      EXPECT_EQ(Mismatches(Coverage(s, c, {true, 16, 0}), c, want, &wanted), 0) << k.name;
    }
  }
}

}  // namespace
}  // namespace patchscan
