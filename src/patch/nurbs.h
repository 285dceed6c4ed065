// NURBS surfaces (RenderMan's NuPatch) as surfaces: a patch of any
// order and knot vector, rational or not, is split at its knots into rational Bézier
// pieces by knot insertion (Boehm's algorithm: every knot inside the parameter range raised
// to multiplicity degree, so that each span's control points are its Bézier points). One
// piece of each non-empty span of [umin,umax] x [vmin,vmax] is one Surface on [0,1]^2,
// evaluated in homogeneous coordinates with the quotient rule for the weight. Pieces that
// share a knot line are one curve there: the scans see no crack between them.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "core/vec.h"
#include "patch/surface_derivs.h"

namespace patchscan {

// A NuPatch as RenderMan gives it: control points u fastest, homogeneous (w x, w y, w z, w)
// ("Pw"; "P" is w = 1), knot vectors of nu + uorder and nv + vorder values, and the
// parameter range rendered.
struct NurbsSurface {
  int nu = 0, uorder = 0, nv = 0, vorder = 0;
  std::vector<double> uknot, vknot;
  double umin = 0.0, umax = 1.0, vmin = 0.0, vmax = 1.0;
  std::vector<Vec4> pw;
};


// The highest order a NuPatch may have here (degree 15): evaluation keeps its Bernstein
// values on the stack.
constexpr int kMaxNurbsOrder = 16;

// One knot span of a NuPatch: a rational tensor-product Bézier patch of degree (p, q) on
// [0,1]^2, control points u fastest and homogeneous. Evaluation allocates nothing.
class NurbsPiece {
 public:
  // (u0,u1) x (v0,v1): where the piece lies in the NuPatch's own parameters.
  NurbsPiece(int uDegree, int vDegree, std::vector<Vec4> pw, double u0, double u1, double v0, double v1);

  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;
  // The control points divided by their weights: with positive weights the piece lies in
  // their convex hull.
  std::span<const Vec3> Hull() const { return hull_; }
  std::string Describe() const;

  int UDegree() const { return p_; }
  int VDegree() const { return q_; }
  const std::vector<Vec4>& Points() const { return pw_; }
  double U0() const { return u0_; }
  double U1() const { return u1_; }
  double V0() const { return v0_; }
  double V1() const { return v1_; }

 private:
  int p_, q_;
  std::vector<Vec4> pw_;
  std::vector<Vec3> hull_;
  double u0_, u1_, v0_, v1_;
};

// The Bézier pieces of `nurbs`, v spans outer, u spans inner. Throws std::invalid_argument
// naming what is wrong: an order below 2 or above kMaxNurbsOrder or above the number of
// control points, a knot vector of the wrong length, decreasing or not finite, a parameter
// range empty or outside the knots' (RenderMan: umin >= uknot[uorder-1], umax <= uknot[nu]),
// a weight that is not positive, a point that is not finite.
std::vector<NurbsPiece> SplitNurbs(const NurbsSurface& nurbs);

// `nurbs` closed along u (alongU) or v, its parameter range there made [lo, hi] by joining
// copies of it one period apart (a knot of multiplicity degree at each joint: the surface is
// as smooth across it as its closed ends meet). A B-rep face on a periodic surface may reach
// past one period, as a thread's face winds round a cylinder twice. Throws
// std::invalid_argument unless the knots are clamped and the first and last rows of control
// points (homogeneous) agree within closeTol; at most 64 periods.
NurbsSurface RepeatPeriods(const NurbsSurface& nurbs, bool alongU, double lo, double hi, double closeTol);

// The rational Bézier segments of a NURBS curve (a trim curve: homogeneous (u w, v w, w)
// points) over [tmin, tmax], each as its degree + 1 control points. Throws
// std::invalid_argument as SplitNurbs does for one direction.
std::vector<std::vector<Vec3>> SplitNurbsCurve(int order, const std::vector<double>& knot, double tmin, double tmax,
                                               const std::vector<Vec3>& points);
// The same for a curve in space: homogeneous (x w, y w, z w, w) points.
std::vector<std::vector<Vec4>> SplitNurbsCurve(int order, const std::vector<double>& knot, double tmin, double tmax,
                                               const std::vector<Vec4>& points);

// The Bernstein polynomials of degree n (n < kMaxNurbsOrder) at t and their first and
// second derivatives, b[0..n].
void Bernstein(int n, double t, double* b, double* db, double* ddb);

// The point at t of a rational Bézier curve given by its homogeneous control points (the
// last coordinate the weight; at most kMaxNurbsOrder of them), and its derivative when `d`
// is given (the quotient rule). Allocates nothing.
template <int N>
Eigen::Matrix<double, N, 1> RationalBezierAt(std::span<const Eigen::Matrix<double, N + 1, 1>> h, double t,
                                             Eigen::Matrix<double, N, 1>* d) {
  double b[kMaxNurbsOrder], db[kMaxNurbsOrder], ddb[kMaxNurbsOrder];
  const int n = static_cast<int>(h.size()) - 1;
  Bernstein(n, t, b, db, ddb);
  Eigen::Matrix<double, N + 1, 1> p = Eigen::Matrix<double, N + 1, 1>::Zero(), dp = p;
  for (int i = 0; i <= n; ++i) {
    p += b[i] * h[static_cast<std::size_t>(i)];
    dp += db[i] * h[static_cast<std::size_t>(i)];
  }
  const Eigen::Matrix<double, N, 1> x = p.template head<N>() / p[N];
  if (d) *d = (dp.template head<N>() - dp[N] * x) / p[N];
  return x;
}

}  // namespace patchscan
