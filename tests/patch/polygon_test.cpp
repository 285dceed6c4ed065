// Polygon triangulation (patch/polygon.h) against the even-odd rule: every point of a
// grid that lies inside the polygon (inside the outline and outside every hole) is covered
// by exactly one triangle, every other point by none; and every triangle turns the way
// the outline does.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "patch/polygon.h"

namespace patchscan {
namespace {

using Loops = std::vector<std::vector<std::uint32_t>>;
using Triangles = std::vector<std::array<std::uint32_t, 3>>;

// Even-odd rule over all loops, in the (x, y) plane.
bool InsideByParity(const std::vector<Vec3>& p, const Loops& loops, const Vec2& q) {
  bool in = false;
  for (const auto& loop : loops)
    for (std::size_t k = 0; k < loop.size(); ++k) {
      const Vec3& a = p[loop[k]];
      const Vec3& b = p[loop[(k + 1) % loop.size()]];
      if ((a.y() > q.y()) != (b.y() > q.y()) && q.x() < a.x() + (q.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
        in = !in;
    }
  return in;
}

double Cross(const Vec3& a, const Vec3& b, const Vec2& q) {
  return (b.x() - a.x()) * (q.y() - a.y()) - (b.y() - a.y()) * (q.x() - a.x());
}

// How many of the triangles cover q strictly inside (q is chosen off every edge).
int Covering(const std::vector<Vec3>& p, const Triangles& t, const Vec2& q) {
  int n = 0;
  for (const auto& tri : t) {
    const double c0 = Cross(p[tri[0]], p[tri[1]], q), c1 = Cross(p[tri[1]], p[tri[2]], q),
                 c2 = Cross(p[tri[2]], p[tri[0]], q);
    if ((c0 > 0 && c1 > 0 && c2 > 0) || (c0 < 0 && c1 < 0 && c2 < 0)) ++n;
  }
  return n;
}

// A grid of points (irrational offsets keep them off the polygons' edges) checked against
// the parity rule; returns the number of points inside.
int ExpectParityCoverage(const std::vector<Vec3>& p, const Loops& loops, const Triangles& t, const char* what) {
  int inside = 0, wrong = 0;
  for (int j = 0; j < 97; ++j)
    for (int i = 0; i < 97; ++i) {
      const Vec2 q(-2.0 + 4.0 * (i + 0.5 * std::numbers::sqrt2) / 97, -2.0 + 4.0 * (j + 0.5 / std::numbers::phi) / 97);
      const int want = InsideByParity(p, loops, q) ? 1 : 0;
      inside += want;
      if (Covering(p, t, q) != want) ++wrong;
    }
  EXPECT_EQ(wrong, 0) << what;
  return inside;
}

// Every triangle turns as the outline does (counter-clockwise in (x, y) for these).
void ExpectCounterClockwise(const std::vector<Vec3>& p, const Triangles& t, const char* what) {
  for (const auto& tri : t)
    EXPECT_GT((p[tri[1]] - p[tri[0]]).cross(p[tri[2]] - p[tri[0]]).z(), 0.0) << what;
}

// A star-shaped polygon around c: n points at angles 2 pi k / n (clockwise if asked) and
// radii from `radius`.
template <class R>
std::vector<std::uint32_t> AddLoop(std::vector<Vec3>* p, int n, Vec2 c, R radius, bool clockwise) {
  std::vector<std::uint32_t> loop;
  for (int k = 0; k < n; ++k) {
    const double a = (clockwise ? -2.0 : 2.0) * std::numbers::pi * k / n;
    const double r = radius(k);
    loop.push_back(static_cast<std::uint32_t>(p->size()));
    p->push_back(Vec3(c.x() + r * std::cos(a), c.y() + r * std::sin(a), 0.0));
  }
  return loop;
}

TEST(Polygon, ConvexPolygonIsAFan) {
  std::vector<Vec3> p;
  Loops loops{AddLoop(&p, 7, Vec2(0, 0), [](int) { return 1.5; }, false)};
  Triangles t;
  EXPECT_EQ(TriangulatePolygon(p, loops, &t), 5u);
  ExpectParityCoverage(p, loops, t, "heptagon");
  ExpectCounterClockwise(p, t, "heptagon");
}

TEST(Polygon, ConcaveStarsAndHoles) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> radius(0.6, 1.8);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Vec3> p;
    const int n = 5 + trial % 40;
    std::vector<double> radii(n);
    for (double& r : radii) r = radius(rng);
    // Given clockwise half of the time: the triangulation follows the outline's turn.
    const bool clockwise = trial % 2 == 1;
    Loops loops{AddLoop(&p, n, Vec2(0, 0), [&](int k) { return radii[k]; }, clockwise)};
    // Up to three holes inside the star's kernel (radius 0.5 cos(pi / 5) at least).
    for (int h = 0; h < trial % 4; ++h) {
      const double a = 2.0 * std::numbers::pi * h / 3 + 0.3;
      loops.push_back(AddLoop(&p, 3 + (trial + h) % 6, Vec2(0.25 * std::cos(a), 0.25 * std::sin(a)),
                              [](int) { return 0.12; }, h % 2 == 0));
    }
    Triangles t;
    TriangulatePolygon(p, loops, &t);
    // A polygon of n points and h holes of m_i points has n + sum m_i + 2 h - 2 triangles.
    std::size_t points = 0;
    for (const auto& l : loops) points += l.size();
    EXPECT_EQ(t.size(), points + 2 * (loops.size() - 1) - 2) << "trial " << trial;
    EXPECT_GT(ExpectParityCoverage(p, loops, t, "star"), 0);
    if (clockwise)
      for (auto& tri : t) std::swap(tri[1], tri[2]);
    ExpectCounterClockwise(p, t, "star");
    if (HasFailure()) {
      ADD_FAILURE() << "first failing trial " << trial;
      return;
    }
  }
}

// A hole whose bridge must not go to the end of the edge its ray meets: a notch of the
// outline (a reflex point) stands between them, and the bridge goes to the notch.
TEST(Polygon, BridgeAroundANotch) {
  const double pts[][2] = {{0, 0}, {12, 0}, {8, 3}, {11, 11}, {5.5, 6}, {4, 12}, {0, 12},  // outline
                           {1, 4.5}, {1, 5.5}, {2, 5}};                                      // hole
  std::vector<Vec3> p;
  for (const auto& q : pts) p.push_back(Vec3(q[0] / 4 - 1.5, q[1] / 4 - 1.5, 0));
  const Loops loops{{0, 1, 2, 3, 4, 5, 6}, {7, 8, 9}};
  Triangles t;
  EXPECT_EQ(TriangulatePolygon(p, loops, &t), 7u + 3u);
  ExpectParityCoverage(p, loops, t, "notch");
  ExpectCounterClockwise(p, t, "notch");
}

// The same polygon in any plane: triangulated in its own plane, turning with its normal.
TEST(Polygon, AnyPlaneAndFarFromTheOrigin) {
  std::vector<Vec3> flat;
  Loops loops{AddLoop(&flat, 12, Vec2(0, 0), [](int k) { return k % 2 ? 0.7 : 1.6; }, false)};
  loops.push_back(AddLoop(&flat, 5, Vec2(0.1, 0), [](int) { return 0.3; }, true));
  Triangles want;
  TriangulatePolygon(flat, loops, &want);
  ExpectParityCoverage(flat, loops, want, "flat");
  const Eigen::Affine3d pose = Eigen::Translation3d(1e5, -3e4, 2e5) *
                               Eigen::AngleAxisd(1.1, Vec3(0.3, -0.8, 0.5).normalized());
  std::vector<Vec3> moved;
  for (const Vec3& q : flat) moved.push_back(pose * q);
  Triangles t;
  TriangulatePolygon(moved, loops, &t);
  ASSERT_EQ(t.size(), want.size());
  const Vec3 normal = NewellNormal(moved, loops[0]);
  EXPECT_NEAR(normal.normalized().dot(pose.linear() * Vec3(0, 0, 1)), 1.0, 1e-12);
  for (const auto& tri : t) EXPECT_GT((moved[tri[1]] - moved[tri[0]]).cross(moved[tri[2]] - moved[tri[0]]).dot(normal), 0.0);
  // Back in the plane, the triangles cover the polygon once.
  std::vector<Vec3> back;
  for (const Vec3& q : moved) back.push_back(pose.inverse() * q);
  ExpectParityCoverage(back, loops, t, "moved");
}

// Newell's normal has twice the area as its length.
TEST(Polygon, NewellNormalIsTheArea) {
  const std::vector<Vec3> square{{0, 0, 0}, {2, 0, 0}, {2, 3, 0}, {0, 3, 0}};
  const std::vector<std::uint32_t> loop{0, 1, 2, 3};
  EXPECT_EQ(NewellNormal(square, loop), Vec3(0, 0, 6));
}

TEST(Polygon, DegenerateInputGivesNothingOrSomethingCovering) {
  Triangles t;
  // Fewer than three points, collinear points, one point repeated: no area.
  const std::vector<Vec3> line{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_EQ(TriangulatePolygon(line, Loops{{0, 1}}, &t), 0u);
  EXPECT_EQ(TriangulatePolygon(line, Loops{{0, 1, 2, 3}}, &t), 0u);
  EXPECT_EQ(TriangulatePolygon(line, Loops{{1, 1, 1}}, &t), 0u);
  EXPECT_EQ(TriangulatePolygon(line, Loops{}, &t), 0u);
  EXPECT_TRUE(t.empty());
  // Points on the outline's edges and repeated points are not triangles of their own.
  const std::vector<Vec3> square{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 2, 0}, {2, 2, 0}, {0, 2, 0}};
  TriangulatePolygon(square, Loops{{0, 1, 2, 3, 4, 5}}, &t);
  double area = 0.0;
  for (const auto& tri : t) area += 0.5 * (square[tri[1]] - square[tri[0]]).cross(square[tri[2]] - square[tri[0]]).z();
  EXPECT_NEAR(area, 4.0, 1e-12);
  // A bow tie (self-intersecting; RenderMan leaves it undefined) ends, with triangles
  // among its own points; a hole outside the outline is dropped.
  t.clear();
  const std::vector<Vec3> bow{{0, 0, 0}, {2, 2, 0}, {2, 0, 0}, {0, 2, 0}, {5, 5, 0}, {6, 5, 0}, {6, 6, 0}};
  TriangulatePolygon(bow, Loops{{0, 1, 2, 3}}, &t);
  for (const auto& tri : t)
    for (const std::uint32_t k : tri) EXPECT_LT(k, 4u);
  t.clear();
  const std::vector<Vec3> withOutside{{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {5, 5, 0}, {5, 6, 0}, {6, 5, 0}};
  EXPECT_EQ(TriangulatePolygon(withOutside, Loops{{0, 1, 2, 3}, {4, 5, 6}}, &t), 2u);
}

// A polygon of thousands of points is triangulated (ear clipping is quadratic in the
// points: this one takes milliseconds).
TEST(Polygon, ManyPoints) {
  std::vector<Vec3> p;
  const int n = 4000;
  Loops loops{AddLoop(&p, n, Vec2(0, 0), [](int k) { return k % 2 ? 1.0 : 1.5; }, false)};
  Triangles t;
  EXPECT_EQ(TriangulatePolygon(p, loops, &t), static_cast<std::size_t>(n - 2));
}

}  // namespace
}  // namespace patchscan
