// RenderMan's Curves (RenderMan Interface 3.2, "Curves"): thin curves drawn as flat
// ribbons that face the camera. Each segment of a curve is a surface of its own, so that
// the trackers, the exact and θ scans and the tessellation all run on it:
//   S(u, v) = C(v) + (u - 1/2) w(v) B(v),   B = unit(C'(v) x D(v)),
// C the segment's cubic (a linear segment is a cubic on a straight line), w its width
// (linear in v between the varying values at its ends), D the direction from the eye to
// C(v) (perspective) or the view axis (orthographic): B is perpendicular to the curve and
// to the line of sight, so the ribbon shows its full width, and its normal faces the eye.
// v runs along the curve and u across it, as RenderMan has them. Derivatives to second
// order are exact (the quotient rule through B's normalisation).
#pragma once

#include <array>
#include <span>
#include <string>

#include "patch/surface_derivs.h"

namespace patchscan {

class CurveRibbon {
 public:
  // The segment's Bézier control points and its widths at v = 0 and v = 1, in world space
  // (the surface's transformation is the identity: a ribbon faces the camera in world
  // space, whatever the curve's own transformation was).
  CurveRibbon(const std::array<Vec3, 4>& bezier, double width0, double width1);

  // Makes this segment begin exactly where `previous` ends, so that their shared edge is
  // the same points, bit for bit: its first point becomes previous's last, and where the
  // curve is smooth there (tangents within kJoinTangentRel), its tangent previous's. At a
  // kink (a Bézier curve's corner) the ribbons meet along the curve but open a wedge, as
  // ribbons do.
  void JoinAfter(const CurveRibbon& previous);

  // The camera the ribbon faces: its eye (perspective) or its view axis (orthographic).
  // Until set, the ribbon faces along +z, as an orthographic camera looking down z would see it.
  void FaceEye(const Vec3& eye);
  void FaceAxis(const Vec3& forward);

  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const;
  // The control points, each widened by half the largest width along every axis.
  std::span<const Vec3> Hull() const { return hull_; }
  std::string Describe() const;

  const std::array<Vec3, 4>& Bezier() const { return b_; }
  double Width0() const { return w0_; }
  double Width1() const { return w1_; }

 private:
  void Prepare();  // the power form and the hull, from the Bézier points and widths

  std::array<Vec3, 4> b_;
  Vec3 a_[4];  // power form: C(v) = a0 + a1 v + a2 v^2 + a3 v^3
  // The ends, taken as they are at v = 0 and v = 1 (not from the power form, whose
  // rounding differs from a neighbour's): points, tangents C'.
  Vec3 t0_, t1_;
  double w0_, w1_;
  bool perspective_ = false;
  Vec3 eye_ = Vec3::Zero(), forward_ = Vec3(0, 0, 1);
  std::array<Vec3, 32> hull_;
};

}  // namespace patchscan
