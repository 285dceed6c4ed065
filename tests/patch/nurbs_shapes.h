// NURBS surfaces for tests: the rational sphere of quadratic arcs, and a wavy rational
// patch with a non-uniform, unclamped knot vector and a knot of full multiplicity.
#pragma once

#include <cmath>

#include "patch/nurbs.h"
#include "patch/trim.h"

namespace patchscan::test {

// The sphere of radius r about the origin: a full circle of four quadratic arcs in u
// (weights sqrt(2)/2 at the square's corners) swept along a half circle of two in v, from
// the south pole (v = 0) to the north (v = 1). du x dv points outwards, as the Sphere
// quadric's normal does.
inline NurbsSurface NurbsSphere(double r) {
  const double s = std::sqrt(0.5);
  const double circle[9][3] = {{1, 0, 1},  {1, 1, s},   {0, 1, 1},  {-1, 1, s}, {-1, 0, 1},
                               {-1, -1, s}, {0, -1, 1}, {1, -1, s}, {1, 0, 1}};
  const double half[5][3] = {{0, -1, 1}, {1, -1, s}, {1, 0, 1}, {1, 1, s}, {0, 1, 1}};  // (radius, z, weight)
  NurbsSurface n;
  n.nu = 9;
  n.uorder = 3;
  n.uknot = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
  n.nv = 5;
  n.vorder = 3;
  n.vknot = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
  for (const auto& h : half)
    for (const auto& c : circle) {
      const double w = h[2] * c[2];
      n.pw.emplace_back(w * r * h[0] * c[0], w * r * h[0] * c[1], w * r * h[1], w);
    }
  return n;
}

// Cubic in u over an unclamped, non-uniform knot vector; quadratic in v with an interior
// knot of multiplicity 2 (a crease-free join of two pieces) and clamped ends; weights from
// 0.4 to 2.2; the range a part of the knots' own.
inline NurbsSurface WavyNurbs() {
  NurbsSurface n;
  n.nu = 6;
  n.uorder = 4;
  n.uknot = {-1.0, -0.5, 0.0, 0.3, 1.0, 1.2, 2.0, 2.6, 3.0, 3.5};
  n.umin = 0.4;
  n.umax = 1.9;
  n.nv = 5;
  n.vorder = 3;
  n.vknot = {0, 0, 0, 0.4, 0.4, 1, 1, 1};
  n.vmin = 0.0;
  n.vmax = 1.0;
  for (int j = 0; j < n.nv; ++j)
    for (int i = 0; i < n.nu; ++i) {
      const double w = 0.4 + 0.3 * ((3 * i + 5 * j) % 7);
      const Vec3 p(i - 2.5, j - 2.0, 0.5 * std::sin(1.3 * i + 0.7 * j));
      n.pw.emplace_back(w * p.x(), w * p.y(), w * p.z(), w);
    }
  return n;
}

// Trim loops in (u,v). A circle about c of radius r: four quadratic arcs, weights
// sqrt(2)/2 at the square's corners, counter-clockwise (clockwise with `reverse`).
inline TrimCurveInput TrimCircle(const Vec2& c, double r, bool reverse = false) {
  const double s = std::sqrt(0.5);
  const double pts[9][3] = {{1, 0, 1},  {1, 1, s},   {0, 1, 1},  {-1, 1, s}, {-1, 0, 1},
                            {-1, -1, s}, {0, -1, 1}, {1, -1, s}, {1, 0, 1}};
  TrimCurveInput in;
  in.order = 3;
  in.knot = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
  for (int k = 0; k < 9; ++k) {
    const auto& p = pts[reverse ? 8 - k : k];
    in.uvw.emplace_back(p[2] * (c.x() + r * p[0]), p[2] * (c.y() + r * p[1]), p[2]);
  }
  return in;
}

// A closed polygon through `corners` as one linear curve (order 2).
inline TrimCurveInput TrimPolygon(const std::vector<Vec2>& corners) {
  TrimCurveInput in;
  in.order = 2;
  const int n = static_cast<int>(corners.size());
  in.knot = {0.0};
  for (int k = 0; k <= n; ++k) in.knot.push_back(k);
  in.knot.push_back(n);
  in.tmax = n;
  for (int k = 0; k <= n; ++k) in.uvw.emplace_back(corners[k % n].x(), corners[k % n].y(), 1.0);
  return in;
}

// A flat square NuPatch of side 2 about the origin in z = 0, u along x and v along y, of
// `spans` x `spans` linear spans (so that trims cross pieces).
inline NurbsSurface FlatSquare(int spans = 1) {
  NurbsSurface n;
  n.nu = n.nv = spans + 1;
  n.uorder = n.vorder = 2;
  n.uknot = {0.0};
  for (int k = 0; k <= spans; ++k) n.uknot.push_back(static_cast<double>(k) / spans);
  n.uknot.push_back(1.0);
  n.vknot = n.uknot;
  for (int j = 0; j <= spans; ++j)
    for (int i = 0; i <= spans; ++i) n.pw.emplace_back(-1.0 + 2.0 * i / spans, -1.0 + 2.0 * j / spans, 0.0, 1.0);
  return n;
}

}  // namespace patchscan::test
