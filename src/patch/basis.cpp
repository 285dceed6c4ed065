#include "patch/basis.h"

namespace patchscan {
namespace {

Mat4 Rows(std::initializer_list<double> v) {
  Mat4 m;
  auto it = v.begin();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = *it++;
  return m;
}

}  // namespace

const Basis& BezierBasis() {
  static const Basis b{Rows({-1, 3, -3, 1, 3, -6, 3, 0, -3, 3, 0, 0, 1, 0, 0, 0}), 3, "bezier"};
  return b;
}

const Basis& BSplineBasis() {
  static const Basis b{Rows({-1, 3, -3, 1, 3, -6, 3, 0, -3, 0, 3, 0, 1, 4, 1, 0}) / 6.0, 1,
                       "b-spline"};
  return b;
}

const Basis& CatmullRomBasis() {
  static const Basis b{Rows({-1, 3, -3, 1, 2, -5, 4, -1, -1, 0, 1, 0, 0, 2, 0, 0}) / 2.0, 1,
                       "catmull-rom"};
  return b;
}

// Geometry order (P0, T0, P1, T1): two end points and their tangents.
const Basis& HermiteBasis() {
  static const Basis b{Rows({2, 1, -2, 1, -3, -2, 3, -1, 0, 1, 0, 0, 1, 0, 0, 0}), 2, "hermite"};
  return b;
}

// Geometry order (a3, a2, a1, a0): the coefficients of t^3, t^2, t, 1.
const Basis& PowerBasis() {
  static const Basis b{Mat4::Identity(), 4, "power"};
  return b;
}

std::optional<Basis> BasisByName(std::string_view name) {
  for (const Basis* b :
       {&BezierBasis(), &BSplineBasis(), &CatmullRomBasis(), &HermiteBasis(), &PowerBasis()})
    if (b->name == name) return *b;
  return std::nullopt;
}

BasisWeights EvaluateBasis(const Basis& basis, double t) {
  const Vec4 tp(t * t * t, t * t, t, 1.0);
  const Vec4 dtp(3 * t * t, 2 * t, 1.0, 0.0);
  const Vec4 d2tp(6 * t, 2.0, 0.0, 0.0);
  return {basis.m.transpose() * tp, basis.m.transpose() * dtp, basis.m.transpose() * d2tp};
}

}  // namespace patchscan
