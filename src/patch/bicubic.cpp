#include "patch/bicubic.h"

#include <Eigen/LU>

namespace patchscan {

namespace {

// Per coordinate, with G(i,j) the control point (i along u, j along v):
// power coefficients  A = Mu G Mv^T   (A(r,s) multiplies u^(3-r) v^(3-s)),
// Bézier points       B = Mb^-1 A Mb^-T.
template <int N>
void ToPowerAndBezier(const std::array<Eigen::Matrix<double, N, 1>, 16>& cv, const Basis& uBasis, const Basis& vBasis,
                      int k, Mat4* a, Mat4* b) {
  static const Mat4 bezierInv = BezierBasis().m.inverse();
  Mat4 g;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) g(i, j) = cv[4 * j + i][k];
  *a = uBasis.m * g * vBasis.m.transpose();
  *b = bezierInv * *a * bezierInv.transpose();
}

}  // namespace

std::array<Vec4, 16> BezierHomogeneous(const std::array<Vec4, 16>& cv, const Basis& uBasis, const Basis& vBasis) {
  if (uBasis.m == BezierBasis().m && vBasis.m == BezierBasis().m) return cv;
  std::array<Vec4, 16> out;
  for (int k = 0; k < 4; ++k) {
    Mat4 a, b;
    ToPowerAndBezier(cv, uBasis, vBasis, k, &a, &b);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) out[4 * j + i][k] = b(i, j);
  }
  return out;
}

BicubicPatch::BicubicPatch(const std::array<Vec3, 16>& cv, const Basis& uBasis,
                           const Basis& vBasis) {
  for (int k = 0; k < 3; ++k) {
    Mat4 a, b;
    ToPowerAndBezier(cv, uBasis, vBasis, k, &a, &b);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) {
        a_[i][j][k] = a(3 - i, 3 - j);
        bezier_[4 * j + i][k] = b(i, j);
      }
  }
  // Bézier input keeps its control points bit for bit (the inverse above rounds).
  if (uBasis.m == BezierBasis().m && vBasis.m == BezierBasis().m) bezier_ = cv;
}

}  // namespace patchscan

namespace patchscan {

unsigned CollapsedEdges(const BicubicPatch& patch) {
  const auto& b = patch.BezierPoints();
  Bounds3 box;
  for (const Vec3& p : b) box.Extend(p);
  const double tol = kCollapsedRel * std::max(box.Diagonal().norm(), 1e-300);
  // Index of the k-th control point along each edge (u fastest: point (i,j) at 4j + i).
  auto index = [](PatchEdge e, int k) {
    switch (e) {
      case PatchEdge::U0: return 4 * k;
      case PatchEdge::U1: return 4 * k + 3;
      case PatchEdge::V0: return k;
      case PatchEdge::V1: return 12 + k;
    }
    return 0;
  };
  unsigned mask = 0;
  for (PatchEdge e : {PatchEdge::U0, PatchEdge::U1, PatchEdge::V0, PatchEdge::V1}) {
    bool collapsed = true;
    for (int k = 1; k < 4; ++k)
      collapsed = collapsed && (b[index(e, k)] - b[index(e, 0)]).norm() <= tol;
    if (collapsed) mask |= 1u << static_cast<int>(e);
  }
  return mask;
}

}  // namespace patchscan
