// Bicubic patches in any cubic basis, and bilinear patches.
#pragma once

#include <array>
#include <span>
#include <string>

#include "patch/basis.h"
#include "patch/surface_derivs.h"

namespace patchscan {

// A bicubic patch S(u,v), (u,v) in [0,1]^2, in object space. Control points are given
// with u varying fastest (point (i,j) at index 4*j + i), as in RenderMan and the .bpt format.
// Prepared once into power form (for evaluation by Horner's rule) and Bézier form (whose
// control hull bounds the patch). Evaluation allocates nothing.
class BicubicPatch {
 public:
  BicubicPatch(const std::array<Vec3, 16>& cv, const Basis& uBasis, const Basis& vBasis);
  explicit BicubicPatch(const std::array<Vec3, 16>& bezierCv)
      : BicubicPatch(bezierCv, BezierBasis(), BezierBasis()) {}

  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;

  // The 16 Bézier control points, u fastest; their convex hull contains the patch.
  const std::array<Vec3, 16>& BezierPoints() const { return bezier_; }
  std::span<const Vec3> Hull() const { return bezier_; }
  std::string Describe() const { return "bicubic patch"; }

 private:
  // a_[i][j] multiplies u^i v^j.
  std::array<std::array<Vec3, 4>, 4> a_;
  std::array<Vec3, 16> bezier_;
};

// The Bézier control points of a bicubic patch given in any basis, homogeneous: a rational
// patch ("Pw") changes basis in (w x, w y, w z, w). Bézier input is returned as it is.
std::array<Vec4, 16> BezierHomogeneous(const std::array<Vec4, 16>& cv, const Basis& uBasis, const Basis& vBasis);

// A bilinear patch through four corners given as in RenderMan: P0 at (0,0), P1 at (1,0),
// P2 at (0,1), P3 at (1,1). Evaluation allocates nothing.
class BilinearPatch {
 public:
  explicit BilinearPatch(const std::array<Vec3, 4>& corners) : p_(corners) {}
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;
  std::span<const Vec3> Hull() const { return p_; }
  std::string Describe() const { return "bilinear patch"; }

 private:
  std::array<Vec3, 4> p_;
};

// ---- inline evaluation (the hot path of every tracker) ----

inline void BicubicPatch::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const bool first = Wants(order, DerivOrder::First);
  const bool second = Wants(order, DerivOrder::Second);
  // Step 1: collapse v. c[i](v) = sum_j a_ij v^j, with its v-derivatives.
  Vec3 c[4], cv[4], cvv[4];
  for (int i = 0; i < 4; ++i) {
    const auto& a = a_[i];
    c[i] = a[0] + v * (a[1] + v * (a[2] + v * a[3]));
    if (first) cv[i] = a[1] + v * (2.0 * a[2] + 3.0 * v * a[3]);
    if (second) cvv[i] = 2.0 * a[2] + 6.0 * v * a[3];
  }
  // Step 2: collapse u by Horner's rule.
  out->p = c[0] + u * (c[1] + u * (c[2] + u * c[3]));
  if (first) {
    out->dpdu = c[1] + u * (2.0 * c[2] + 3.0 * u * c[3]);
    out->dpdv = cv[0] + u * (cv[1] + u * (cv[2] + u * cv[3]));
  }
  if (second) {
    out->d2pdu2 = 2.0 * c[2] + 6.0 * u * c[3];
    out->d2pduv = cv[1] + u * (2.0 * cv[2] + 3.0 * u * cv[3]);
    out->d2pdv2 = cvv[0] + u * (cvv[1] + u * (cvv[2] + u * cvv[3]));
  }
}

inline void BilinearPatch::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const Vec3 e0 = p_[1] - p_[0];  // along u at v = 0
  const Vec3 e1 = p_[3] - p_[2];  // along u at v = 1
  const Vec3 bottom = p_[0] + u * e0;
  const Vec3 top = p_[2] + u * e1;
  out->p = bottom + v * (top - bottom);
  if (Wants(order, DerivOrder::First)) {
    out->dpdu = e0 + v * (e1 - e0);
    out->dpdv = top - bottom;
  }
  if (Wants(order, DerivOrder::Second)) {
    out->d2pdu2 = Vec3::Zero();
    out->d2pduv = e1 - e0;
    out->d2pdv2 = Vec3::Zero();
  }
}

}  // namespace patchscan

namespace patchscan {

// The four boundary curves of a patch on [0,1]^2.
enum class PatchEdge { U0 = 0, U1 = 1, V0 = 2, V1 = 3 };
inline const char* EdgeName(PatchEdge e) {
  static const char* const kNames[] = {"u=0", "u=1", "v=0", "v=1"};
  return kNames[static_cast<int>(e)];
}

// Collapsed (degenerate) edges of a bicubic patch: boundary curves whose four Bézier
// control points coincide, so the whole edge is one point (the teapot's lid apex).
// Points count as equal within kCollapsedRel of the patch's extent (surface_derivs.h): exact
// data that was meant to meet differs only by rounding of its last digits. Bit i is PatchEdge i.
unsigned CollapsedEdges(const BicubicPatch& patch);

}  // namespace patchscan
