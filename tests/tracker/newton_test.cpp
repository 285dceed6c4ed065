// Newton solvers: convergence order, damping, caps, domain rules, and no NaN ever; the
// bracketed crossing on a monotone piece (tracker births and repairs).
#include <gtest/gtest.h>

#include <random>

#include "tracker/monotone_curve.h"
#include "tracker/newton.h"

namespace patchscan {
namespace {

TEST(Newton1, ConvergesQuadratically) {
  // f = t^2 - 2: e_{k+1} = e_k^2 / (2 t) near the root, so e_{k+1} / e_k^2 -> 1/(2 sqrt 2).
  auto f = [](double t, double* v, double* d) { *v = t * t - 2; *d = 2 * t; };
  const double root = std::sqrt(2.0);
  double prev = 0.0;
  for (int k = 1; k <= 4; ++k) {
    NewtonOptions o;
    o.maxIterations = k;
    const auto r = SolveNewton1(f, 1.0, 0.0, 2.0, 0.0, o);  // tolerance 0: run every iteration
    const double e = std::abs(r.t - root);
    if (k >= 2 && prev > 1e-7) {
      EXPECT_NEAR(e / (prev * prev), 1.0 / (2 * root), 0.1) << "k " << k;
    }
    prev = e;
  }
  const auto r = SolveNewton1(f, 1.0, 0.0, 2.0, 1e-12);
  EXPECT_EQ(r.status, NewtonStatus::Converged);
  EXPECT_LE(r.iterations, 6);
  EXPECT_NEAR(r.t, root, 1e-12);
}

TEST(Newton1, DampingRescuesADivergentStart) {
  // Undamped Newton on atan diverges from |t0| > 1.39; halving keeps |f| decreasing.
  auto f = [](double t, double* v, double* d) { *v = std::atan(t); *d = 1 / (1 + t * t); };
  const auto r = SolveNewton1(f, 3.0, -10.0, 10.0, 1e-12);
  EXPECT_EQ(r.status, NewtonStatus::Converged);
  EXPECT_NEAR(r.t, 0.0, 1e-12);
}

TEST(Newton1, FailuresAreStatusesNotNaN) {
  // No root: t^2 + 1 stalls at its minimum, where no step decreases it.
  auto noRoot = [](double t, double* v, double* d) { *v = t * t + 1; *d = 2 * t; };
  auto r = SolveNewton1(noRoot, 0.7, -5.0, 5.0, 1e-9);
  EXPECT_NE(r.status, NewtonStatus::Converged);
  EXPECT_TRUE(std::isfinite(r.t) && std::isfinite(r.f));
  // Root outside the domain: Fail says so, Clip pins at the boundary and says so.
  auto outside = [](double t, double* v, double* d) { *v = t - 2; *d = 1; };
  NewtonOptions fail;
  fail.domain = DomainRule::Fail;
  EXPECT_EQ(SolveNewton1(outside, 0.5, 0.0, 1.0, 1e-9, fail).status, NewtonStatus::LeftDomain);
  r = SolveNewton1(outside, 0.5, 0.0, 1.0, 1e-9);
  EXPECT_EQ(r.status, NewtonStatus::LeftDomain);
  EXPECT_EQ(r.t, 1.0);
  // A NaN from the function never escapes.
  auto nan = [](double t, double* v, double* d) { *v = t > 0.6 ? NAN : t - 0.7; *d = 1; };
  r = SolveNewton1(nan, 0.5, 0.0, 1.0, 1e-9);
  EXPECT_NE(r.status, NewtonStatus::Converged);
  EXPECT_TRUE(std::isfinite(r.t) && std::isfinite(r.f));
  // Zero derivative.
  auto flat = [](double, double* v, double* d) { *v = 1; *d = 0; };
  EXPECT_EQ(SolveNewton1(flat, 0.5, 0.0, 1.0, 1e-9).status, NewtonStatus::Singular);
}

// Circle x^2 + y^2 = r2 meets the line x - y = c.
struct CircleLine {
  double r2, c;
  void operator()(const Vec2& p, Vec2* f, Mat2* j) const {
    *f = Vec2(p.squaredNorm() - r2, p.x() - p.y() - c);
    *j << 2 * p.x(), 2 * p.y(), 1, -1;
  }
};

// A tracker is born at the top of its piece, where y' may vanish: the crossing of y = t^2
// with 0.09 on [0, 1] from there. Bisection to rounding took ~53 evaluations; Newton kept
// in the bracket reaches the root to a few ulps in under a dozen (kEvaluationsAtMost).
TEST(CrossingOnPiece, NewtonInsideTheBracketFindsTheRootToRounding) {
  constexpr int kEvaluationsAtMost = 12;
  constexpr double kUlps = 4e-16;  // t in [0, 1]: a few units in the last place
  int evaluations = 0;
  auto f = [&](double t, double* v, double* d) {
    ++evaluations;
    *v = t * t - 0.09;
    *d = 2 * t;
  };
  EXPECT_NEAR(CrossingOnPiece(f, 0.0, 1.0, 1e-9), 0.3, kUlps);
  EXPECT_LE(evaluations, kEvaluationsAtMost);
  // Decreasing on its piece, and with the root at a piece end.
  evaluations = 0;
  auto g = [&](double t, double* v, double* d) {
    ++evaluations;
    *v = std::cos(t) - std::cos(1.0);
    *d = -std::sin(t);
  };
  EXPECT_NEAR(CrossingOnPiece(g, 0.0, 1.0, 1e-9), 1.0, kUlps);
  EXPECT_LE(evaluations, 60);  // bisection toward an end: about one per bit
}

// Where Newton's step leaves the bracket or stalls (a flat run, a NaN derivative) the
// bracket is bisected, so the search always ends on the crossing.
TEST(CrossingOnPiece, BisectsWhereNewtonCannotStep) {
  // atan: Newton from far out overshoots the bracket.
  auto a = [](double t, double* v, double* d) {
    *v = std::atan(40.0 * (t - 0.7));
    *d = 40.0 / (1.0 + 1600.0 * (t - 0.7) * (t - 0.7));
  };
  EXPECT_NEAR(CrossingOnPiece(a, 0.0, 1.0, 1e-12), 0.7, 1e-15);
  // No derivative at all.
  auto n = [](double t, double* v, double* d) {
    *v = t - 0.123;
    *d = NAN;
  };
  EXPECT_NEAR(CrossingOnPiece(n, 0.0, 1.0, 1e-12), 0.123, 1e-15);
  // A cube root's derivative is infinite at its root: steps that do not halve fall back.
  auto c = [](double t, double* v, double* d) {
    const double x = t - 0.41;
    *v = std::cbrt(x);
    *d = x == 0.0 ? INFINITY : 1.0 / (3.0 * std::cbrt(x * x));
  };
  EXPECT_NEAR(CrossingOnPiece(c, 0.0, 1.0, 1e-6), 0.41, 1e-12);
}

TEST(Newton2, ConvergesQuadraticallyToTheIntersection) {
  const CircleLine f{0.5, 0.1};
  // The root with x, y > 0: x = (c + sqrt(2 r2 - c^2)) / 2.
  const double x = (0.1 + std::sqrt(1.0 - 0.01)) / 2;
  const Vec2 root(x, x - 0.1);
  double prev = 0.0;
  for (int k = 1; k <= 4; ++k) {
    NewtonOptions o;
    o.maxIterations = k;
    const auto r = SolveNewton2(f, Vec2(0.9, 0.9), Vec2::Zero(), o);
    const double e = (r.uv - root).norm();
    if (k >= 2 && prev > 1e-6) {
      EXPECT_LT(e, 2.0 * prev * prev) << "k " << k;  // quadratic
    }
    prev = e;
  }
  const auto r = SolveNewton2(f, Vec2(0.9, 0.9), Vec2(1e-12, 1e-12));
  EXPECT_EQ(r.status, NewtonStatus::Converged);
  EXPECT_LE((r.uv - root).norm(), 1e-11);
  EXPECT_LE(r.iterations, 6);
}

TEST(Newton2, DomainRulesAndSingularities) {
  // The intersection at negative coordinates is outside [0,1]^2.
  const CircleLine f{0.5, 0.1};
  NewtonOptions fail;
  fail.domain = DomainRule::Fail;
  auto r = SolveNewton2(f, Vec2(0.0, 0.05), Vec2(1e-12, 1e-12), fail);
  EXPECT_TRUE(r.status == NewtonStatus::LeftDomain || r.status == NewtonStatus::Converged);
  // Tangent line: the Jacobian is singular at the single touching point; no NaN.
  const CircleLine tangent{0.5, 1.0};  // x - y = 1 touches x^2 + y^2 = 1/2 at (1/2, -1/2)
  r = SolveNewton2(tangent, Vec2(0.5, 0.0), Vec2(1e-14, 1e-14));
  EXPECT_TRUE(r.uv.allFinite() && r.f.allFinite());
  EXPECT_NE(r.status, NewtonStatus::Converged);
  // A function that returns NaN beyond u = 0.6.
  auto nan = [](const Vec2& p, Vec2* v, Mat2* j) {
    *v = p.x() > 0.6 ? Vec2(NAN, NAN) : Vec2(p.x() - 0.8, p.y() - 0.5);
    *j = Mat2::Identity();
  };
  r = SolveNewton2(nan, Vec2(0.5, 0.5), Vec2(1e-9, 1e-9));
  EXPECT_NE(r.status, NewtonStatus::Converged);
  EXPECT_TRUE(r.uv.allFinite() && r.f.allFinite());
}

TEST(Newton2, RandomCubicsNeverLoopNorNaN) {
  // Random cubic systems from random starts: every run ends within its cap with finite
  // numbers and a status.
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> d(-1, 1), s(0, 1);
  for (int n = 0; n < 2000; ++n) {
    double a[8];
    for (double& x : a) x = d(rng);
    auto f = [&](const Vec2& p, Vec2* v, Mat2* j) {
      const double u = p.x(), w = p.y();
      *v = Vec2(a[0] * u * u * u + a[1] * w + a[2] * u * w + a[3],
                 a[4] * w * w * w + a[5] * u + a[6] * u * u + a[7]);
      *j << 3 * a[0] * u * u + a[2] * w, a[1] + a[2] * u, a[5] + 2 * a[6] * u, 3 * a[4] * w * w;
    };
    const auto r = SolveNewton2(f, Vec2(s(rng), s(rng)), Vec2(1e-10, 1e-10));
    ASSERT_TRUE(r.uv.allFinite() && r.f.allFinite()) << "system " << n;
    ASSERT_LE(r.iterations, NewtonOptions{}.maxIterations);
    ASSERT_TRUE((r.uv.array() >= 0).all() && (r.uv.array() <= 1).all());
  }
}

}  // namespace
}  // namespace patchscan
