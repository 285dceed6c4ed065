// Trim loops (patch/trim.h): the odd winding rule against analytic answers for circles,
// polygons, nested and separate loops; the sense; loops refused; the pieces of a NuPatch a
// trim reaches, keeps whole or drops.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "nurbs_shapes.h"
#include "patch/trim.h"

namespace patchscan {
namespace {

using test::TrimCircle;
using test::TrimPolygon;

// Points this near a curve are not asked about: the answer there is the last bits of a
// bisection (rounding, 1e-15) and of the exporter's numbers.
constexpr double kNearCurve = 1e-9;

// Every point of a 101 x 101 grid over [-0.1, 1.1]^2 and some on the loops' extreme rows
// and columns (where rays pass through joints and turning points of the curves).
template <class Want>
void ExpectParity(const TrimLoops& loops, Want&& want, const char* name) {
  int asked = 0, wrong = 0;
  auto check = [&](const Vec2& p) {
    const auto w = want(p);  // {inside, distance to the nearest curve}
    if (w.second < kNearCurve) return;
    ++asked;
    if (loops.InsideLoops(p) != w.first && ++wrong <= 5) ADD_FAILURE() << name << ": (" << p.x() << ", " << p.y() << ")";
  };
  for (int j = 0; j <= 100; ++j)
    for (int i = 0; i <= 100; ++i) check(Vec2(-0.1 + 1.2 * i / 100, -0.1 + 1.2 * j / 100));
  for (const double v : {0.1, 0.2, 0.25, 0.5, 0.75, 0.8, 0.9})
    for (int i = 0; i <= 200; ++i) check(Vec2(-0.1 + 1.2 * i / 200, v));
  EXPECT_EQ(wrong, 0) << name << ": " << asked << " points asked";
}

TEST(Trim, CircleByTheOddWindingRule) {
  const Vec2 c(0.5, 0.5);
  for (const bool reverse : {false, true}) {
    const TrimLoops loops({{TrimCircle(c, 0.3, reverse)}}, false);
    ExpectParity(loops, [&](const Vec2& p) {
      const double d = (p - c).norm() - 0.3;
      return std::pair(d < 0.0, std::abs(d));
    }, reverse ? "circle, clockwise" : "circle");
    // The sense: "outside" keeps all but the disc, "inside" only the disc.
    EXPECT_FALSE(loops.Kept(c));
    EXPECT_TRUE(loops.Kept(Vec2(0.05, 0.05)));
    EXPECT_TRUE(loops.WithSense(true).Kept(c));
    EXPECT_FALSE(loops.WithSense(true).Kept(Vec2(0.05, 0.05)));
  }
}

double SegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
  return (p - (a + t * (b - a))).norm();
}

TEST(Trim, NestedAndSeparateLoops) {
  // A square ring [0.1, 0.9]^2 holding a circle (a hole in it) holding a small square (an
  // island in the hole), and a separate triangle: inside the loops is odd nesting.
  const std::vector<Vec2> outer = {{0.1, 0.1}, {0.7, 0.1}, {0.7, 0.9}, {0.1, 0.9}};
  const std::vector<Vec2> island = {{0.35, 0.45}, {0.45, 0.45}, {0.45, 0.55}, {0.35, 0.55}};
  const std::vector<Vec2> triangle = {{0.75, 0.2}, {1.0, 0.5}, {0.75, 0.8}};
  const Vec2 c(0.4, 0.5);
  const double r = 0.2;
  const TrimLoops loops({{TrimPolygon(outer)}, {TrimCircle(c, r)}, {TrimPolygon(island)}, {TrimPolygon(triangle)}}, false);
  EXPECT_EQ(loops.Loops(), 4);
  auto polygon = [](const std::vector<Vec2>& q, const Vec2& p, double* distance) {
    bool in = false;
    for (std::size_t k = 0; k < q.size(); ++k) {
      const Vec2 &a = q[k], &b = q[(k + 1) % q.size()];
      *distance = std::min(*distance, SegmentDistance(p, a, b));
      if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
        in = !in;
    }
    return in;
  };
  ExpectParity(loops, [&](const Vec2& p) {
    double d = std::abs((p - c).norm() - r);
    const int depth = polygon(outer, p, &d) + ((p - c).norm() < r) + polygon(island, p, &d) + polygon(triangle, p, &d);
    return std::pair(depth % 2 == 1, d);
  }, "nested loops");
}

TEST(Trim, LoopsThatDoNotCloseAreRefused) {
  auto message = [](const std::vector<std::vector<TrimCurveInput>>& loops) {
    try {
      TrimLoops t(loops, false);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  TrimCurveInput open = TrimPolygon({{0, 0}, {1, 0}, {1, 1}});
  open.uvw.back() = Vec3(0.5, 0.5, 1.0);
  EXPECT_EQ(message({{open}}), "loop 1 is not closed: a curve ends at (0.5, 0.5) and the next starts at (0, 0)");
  // Two curves not head to tail.
  TrimCurveInput a = TrimPolygon({{0, 0}, {1, 0}}), b = TrimPolygon({{1, 1}, {0, 1}});
  a.knot = {0, 0, 1, 1};
  a.tmax = 1;
  a.uvw.pop_back();
  b.knot = {0, 0, 1, 1};
  b.tmax = 1;
  b.uvw.pop_back();
  EXPECT_EQ(message({{a, b}}), "loop 1 is not closed: a curve ends at (1, 0) and the next starts at (1, 1)");
  TrimCurveInput bad = TrimCircle(Vec2(0.5, 0.5), 0.2);
  bad.uvw[3].z() = 0.0;
  EXPECT_EQ(message({{TrimCircle(Vec2(0.5, 0.5), 0.1)}, {bad}}),
            "loop 2, curve 1: control point 3 has weight 0 (weights are positive)");
  bad = TrimCircle(Vec2(0.5, 0.5), 0.2);
  bad.order = 17;
  EXPECT_EQ(message({{bad}}), "loop 1, curve 1: order 17 is not from 2 to 16");
  EXPECT_EQ(message({{}}), "loop 1 has no curves");
}

TEST(Trim, PiecesAreTrimmedKeptWholeOrDropped) {
  // A 4 x 4 grid of pieces; a circle within the piece [0.25, 0.5] x [0.5, 0.75] and a
  // square covering the piece [0.75, 1] x [0, 0.25] with room to spare.
  std::vector<NurbsPiece> pieces = SplitNurbs(test::FlatSquare(4));
  ASSERT_EQ(pieces.size(), 16u);
  auto loops = std::make_shared<const TrimLoops>(
      std::vector<std::vector<TrimCurveInput>>{{TrimCircle(Vec2(0.375, 0.625), 0.1)},
                                               {TrimPolygon({{0.7, -0.1}, {1.1, -0.1}, {1.1, 0.3}, {0.7, 0.3}})}},
      false);
  const std::vector<TrimmedPiece> kept = TrimPieces(loops, std::move(pieces));
  int trimmed = 0;
  for (const auto& [p, trim] : kept) {
    EXPECT_FALSE(p.U0() == 0.75 && p.V0() == 0.0) << "the covered piece is dropped";
    if (!trim) continue;
    ++trimmed;
    const bool circle = p.U0() == 0.25 && p.V0() == 0.5;
    const bool nearSquare = p.U1() == 0.75 || p.V0() == 0.25;  // pieces the square's box reaches
    EXPECT_TRUE(circle || nearSquare) << p.Describe();
    if (circle) {
      EXPECT_FALSE(trim->Kept(Vec2(0.5, 0.5)));  // the circle's centre, in the piece's own (u,v)
      EXPECT_TRUE(trim->Kept(Vec2(0.02, 0.02)));
    }
  }
  EXPECT_EQ(kept.size(), 15u);
  EXPECT_GE(trimmed, 1);
}

}  // namespace
}  // namespace patchscan
