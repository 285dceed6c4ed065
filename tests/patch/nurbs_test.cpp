// NURBS pieces against an independent evaluation of the whole NuPatch (the Cox-de Boor
// recursion on the knots as given, no knot insertion), the rational sphere against the
// unit sphere, the Bernstein derivatives against differences, and malformed patches
// refused by name.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "patch/nurbs.h"
#include "patch/nurbs_shapes.h"

namespace patchscan {
namespace {

// B-spline basis function k of order `order` at t by the Cox-de Boor recursion, with the
// half-open spans [t_k, t_k+1) except that the domain's last span is closed at its end.
double CoxDeBoor(const std::vector<double>& t, int k, int order, double x, double domainEnd) {
  if (order == 1) {
    const double a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>(k + 1)];
    if (a < b && ((x >= a && x < b) || (x == domainEnd && b == domainEnd))) return 1.0;
    return 0.0;
  }
  double sum = 0.0;
  const double a = t[static_cast<std::size_t>(k)], b = t[static_cast<std::size_t>(k + order - 1)];
  const double c = t[static_cast<std::size_t>(k + 1)], d = t[static_cast<std::size_t>(k + order)];
  if (b > a) sum += (x - a) / (b - a) * CoxDeBoor(t, k, order - 1, x, domainEnd);
  if (d > c) sum += (d - x) / (d - c) * CoxDeBoor(t, k + 1, order - 1, x, domainEnd);
  return sum;
}

Vec3 Direct(const NurbsSurface& n, double u, double v) {
  Vec4 h = Vec4::Zero();
  const double uEnd = n.uknot[static_cast<std::size_t>(n.nu)], vEnd = n.vknot[static_cast<std::size_t>(n.nv)];
  for (int j = 0; j < n.nv; ++j) {
    const double bv = CoxDeBoor(n.vknot, j, n.vorder, v, vEnd);
    if (bv == 0.0) continue;
    for (int i = 0; i < n.nu; ++i) h += bv * CoxDeBoor(n.uknot, i, n.uorder, u, uEnd) * n.pw[static_cast<std::size_t>(j * n.nu + i)];
  }
  return h.head<3>() / h.w();
}

// Knot insertion and the recursion agree to rounding: the points are O(1).
constexpr double kAgree = 1e-12;

void ExpectPiecesMatchDirect(const NurbsSurface& n, std::size_t expectedPieces, const std::string& name) {
  const std::vector<NurbsPiece> pieces = SplitNurbs(n);
  ASSERT_EQ(pieces.size(), expectedPieces) << name;
  double coveredU = 0.0, coveredV = 0.0;
  for (const NurbsPiece& piece : pieces) {
    if (piece.V0() == pieces.front().V0()) coveredU += piece.U1() - piece.U0();
    if (piece.U0() == pieces.front().U0()) coveredV += piece.V1() - piece.V0();
    for (int j = 0; j <= 8; ++j)
      for (int i = 0; i <= 8; ++i) {
        const double s = i / 8.0, t = j / 8.0;
        SurfaceDerivs d;
        piece.Evaluate(s, t, DerivOrder::Position, &d);
        const Vec3 want = Direct(n, piece.U0() + s * (piece.U1() - piece.U0()), piece.V0() + t * (piece.V1() - piece.V0()));
        EXPECT_LE((d.p - want).norm(), kAgree) << name << ", " << piece.Describe() << " at (" << s << ", " << t << ")";
      }
  }
  // The pieces tile the range.
  EXPECT_NEAR(coveredU, n.umax - n.umin, 1e-15) << name;
  EXPECT_NEAR(coveredV, n.vmax - n.vmin, 1e-15) << name;
}

TEST(Nurbs, PiecesAreTheNuPatchAtTheirParameters) {
  ExpectPiecesMatchDirect(test::NurbsSphere(1.0), 8, "sphere");
  // u: knots inside [0.4, 1.9] are 1.0 and 1.2, so three spans; v: two.
  ExpectPiecesMatchDirect(test::WavyNurbs(), 6, "wavy");
  NurbsSurface part = test::NurbsSphere(2.0);
  part.umin = 0.1;
  part.umax = 0.3;  // across the knot at 0.25
  part.vmin = 0.2;
  part.vmax = 0.45;
  ExpectPiecesMatchDirect(part, 2, "a part of the sphere");
}

// A closed surface repeated past its period is the same surface at the parameter wrapped
// into one period, in either direction; an open one is refused.
TEST(Nurbs, RepeatedPeriodsAreTheSurfaceWrapped) {
  const NurbsSurface sphere = test::NurbsSphere(1.5);
  const auto wrapped = [](double t) { return t - std::floor(t); };
  const NurbsSurface u = RepeatPeriods(sphere, true, -0.3, 2.2, 1e-12);
  EXPECT_EQ(u.umin, -0.3);
  EXPECT_EQ(u.umax, 2.2);
  EXPECT_EQ(u.nu, 4 * (sphere.nu - 1) + 1);  // periods [-1, 0] to [2, 3]
  for (double x : {-0.3, -0.01, 0.37, 1.0, 1.62, 2.2})
    for (double y : {0.0, 0.3, 0.8}) EXPECT_LE((Direct(u, x, y) - Direct(sphere, wrapped(x), y)).norm(), kAgree) << x << ", " << y;
  ExpectPiecesMatchDirect(u, 11 * 2, "sphere repeated along u");  // knots -0.25 to 2 cut the range in 11
  // Along v: the sphere's circle in u becomes the closed direction of its transpose.
  NurbsSurface t = sphere;
  std::swap(t.nu, t.nv), std::swap(t.uorder, t.vorder), std::swap(t.uknot, t.vknot);
  for (int j = 0; j < sphere.nv; ++j)
    for (int i = 0; i < sphere.nu; ++i)
      t.pw[static_cast<std::size_t>(i * sphere.nv + j)] = sphere.pw[static_cast<std::size_t>(j * sphere.nu + i)];
  const NurbsSurface v = RepeatPeriods(t, false, 0.5, 1.75, 1e-12);
  for (double y : {0.5, 0.99, 1.2, 1.75}) EXPECT_LE((Direct(v, 0.4, y) - Direct(t, 0.4, wrapped(y))).norm(), kAgree) << y;
  // v runs pole to pole: not closed.
  EXPECT_THROW(RepeatPeriods(sphere, false, 0.0, 1.5, 1e-12), std::invalid_argument);
}

TEST(Nurbs, TheRationalSphereIsTheSphere) {
  // On the unit sphere to rounding, with du x dv along the outward normal wherever it is
  // not collapsed (the poles: the first and last rows of pieces at v = 0 and v = 1).
  constexpr double kOnSphere = 1e-14, kNormal = 1e-12;
  for (const NurbsPiece& piece : SplitNurbs(test::NurbsSphere(1.0)))
    for (int j = 0; j <= 10; ++j)
      for (int i = 0; i <= 10; ++i) {
        SurfaceDerivs d;
        piece.Evaluate(i / 10.0, j / 10.0, DerivOrder::First, &d);
        EXPECT_NEAR(d.p.norm(), 1.0, kOnSphere);
        const Vec3 n = d.dpdu.cross(d.dpdv);
        if (n.norm() < 1e-6) continue;
        EXPECT_LE((n.normalized() - d.p).norm(), kNormal) << piece.Describe();
      }
}

TEST(Nurbs, BernsteinDerivativesMatchDifferences) {
  // Central differences: truncation h^2/6 times the third derivative (h^2/12 times the
  // fourth for the second), where the j-th derivative of a degree-n Bernstein polynomial is
  // at most (2n)^j (j differences of degree-(n-j) polynomials); rounding 1e-16/h (1e-16/h^2).
  constexpr double kH1 = 1e-6, kH2 = 1e-4;
  for (int n = 0; n < kMaxNurbsOrder; ++n) {
    const double first = kH1 * kH1 / 6 * std::pow(2.0 * n, 3) + 1e-9, second = kH2 * kH2 / 12 * std::pow(2.0 * n, 4) + 1e-7;
    for (const double t : {0.0, 0.13, 0.5, 0.91, 1.0}) {
      double b[kMaxNurbsOrder], db[kMaxNurbsOrder], ddb[kMaxNurbsOrder], scratch[2][kMaxNurbsOrder];
      double p1[kMaxNurbsOrder], m1[kMaxNurbsOrder], p2[kMaxNurbsOrder], m2[kMaxNurbsOrder];
      Bernstein(n, t, b, db, ddb);
      Bernstein(n, t + kH1, p1, scratch[0], scratch[1]);
      Bernstein(n, t - kH1, m1, scratch[0], scratch[1]);
      Bernstein(n, t + kH2, p2, scratch[0], scratch[1]);
      Bernstein(n, t - kH2, m2, scratch[0], scratch[1]);
      double sum = 0.0;
      for (int k = 0; k <= n; ++k) {
        sum += b[k];
        EXPECT_NEAR(db[k], (p1[k] - m1[k]) / (2 * kH1), first) << "degree " << n << ", k " << k << ", t " << t;
        EXPECT_NEAR(ddb[k], (p2[k] - 2 * b[k] + m2[k]) / (kH2 * kH2), second)
            << "degree " << n << ", k " << k << ", t " << t;
      }
      EXPECT_NEAR(sum, 1.0, 1e-14);
    }
  }
}

TEST(Nurbs, MalformedPatchesAreRefusedByName) {
  auto refused = [](const NurbsSurface& n) {
    try {
      SplitNurbs(n);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  const NurbsSurface good = test::NurbsSphere(1.0);
  struct Case {
    std::function<void(NurbsSurface&)> change;
    std::string message;
  };
  const Case cases[] = {
      {[](NurbsSurface& n) { n.uorder = 1; }, "uorder 1 is not from 2 to 16"},
      {[](NurbsSurface& n) { n.vorder = 17; }, "vorder 17 is not from 2 to 16"},
      {[](NurbsSurface& n) { n.uknot.pop_back(); }, "uknot has 11 values, nu + uorder = 12"},
      {[](NurbsSurface& n) { n.vknot[4] = 0.2; }, "vknot decreases at value 4"},
      {[](NurbsSurface& n) { n.uknot[5] = NAN; }, "uknot value 5 is not finite"},
      {[](NurbsSurface& n) { n.umin = 0.5, n.umax = 0.5; }, "umin 0.5 and umax 0.5 are not a range"},
      {[](NurbsSurface& n) { n.vmax = 1.5; }, "vrange [0, 1.5] is not within the knots' [0, 1]"},
      {[](NurbsSurface& n) { n.pw[3].w() = 0.0; }, "control point 3 has weight 0 (weights are positive)"},
      {[](NurbsSurface& n) { n.pw[7].x() = INFINITY; }, "control point 7 is not finite"},
      {[](NurbsSurface& n) { n.pw.pop_back(); }, "44 control points, nu x nv = 45"},
      {[](NurbsSurface& n) {
         n.nv = 2;
         n.vknot = {0, 0, 0, 1, 1};
       },
       "nv 2 control points are fewer than the vorder 3"},
  };
  for (const Case& c : cases) {
    NurbsSurface n = good;
    c.change(n);
    EXPECT_NE(refused(n).find(c.message), std::string::npos) << refused(n) << " | wanted " << c.message;
  }
}

}  // namespace
}  // namespace patchscan
