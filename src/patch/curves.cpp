#include "patch/curves.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

namespace patchscan {
namespace {

// Below this |C' x D| relative to |C'| |D| the curve runs along the line of sight: no
// direction across it faces the eye better than another, and one perpendicular to the
// line of sight is taken (the ribbon is seen end-on there, a point on the screen).
constexpr double kEndOnRel = 1e-12;
// Two segments' tangents at their joint that differ by less than this, relative, are one
// smooth curve's (a b-spline's or Catmull-Rom's, up to rounding).
constexpr double kJoinTangentRel = 1e-9;

}  // namespace

CurveRibbon::CurveRibbon(const std::array<Vec3, 4>& bezier, double width0, double width1)
    : b_(bezier), w0_(width0), w1_(width1) {
  Prepare();
  t0_ = a_[1];
  t1_ = 3.0 * (b_[3] - b_[2]);
}

void CurveRibbon::Prepare() {
  // Bernstein to power form.
  a_[0] = b_[0];
  a_[1] = 3.0 * (b_[1] - b_[0]);
  a_[2] = 3.0 * (b_[2] - 2.0 * b_[1] + b_[0]);
  a_[3] = b_[3] - 3.0 * b_[2] + 3.0 * b_[1] - b_[0];
  const double h = 0.5 * std::max(std::abs(w0_), std::abs(w1_));
  for (int k = 0; k < 4; ++k)
    for (int c = 0; c < 8; ++c)
      hull_[8 * k + c] = b_[k] + h * Vec3((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
}

void CurveRibbon::JoinAfter(const CurveRibbon& previous) {
  b_[0] = previous.b_[3];
  w0_ = previous.w1_;
  Prepare();
  if ((t0_ - previous.t1_).norm() <= kJoinTangentRel * previous.t1_.norm()) t0_ = previous.t1_;
}

void CurveRibbon::FaceEye(const Vec3& eye) {
  perspective_ = true;
  eye_ = eye;
}

void CurveRibbon::FaceAxis(const Vec3& forward) {
  perspective_ = false;
  forward_ = forward.normalized();
}

void CurveRibbon::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  // The ends exactly as a neighbour has them.
  const Vec3 c = v == 0.0 ? b_[0] : v == 1.0 ? b_[3] : Vec3(a_[0] + v * (a_[1] + v * (a_[2] + v * a_[3])));
  const Vec3 c1 = v == 0.0 ? t0_ : v == 1.0 ? t1_ : Vec3(a_[1] + v * (2.0 * a_[2] + 3.0 * v * a_[3]));
  const Vec3 c2 = 2.0 * a_[2] + 6.0 * v * a_[3];
  const Vec3 c3 = 6.0 * a_[3];
  // The line of sight and its derivatives along the curve.
  const Vec3 d = perspective_ ? Vec3(c - eye_) : forward_;
  const Vec3 d1 = perspective_ ? c1 : Vec3::Zero();
  const Vec3 d2 = perspective_ ? c2 : Vec3::Zero();
  // N = C' x D, B = N / |N|, and their derivatives:
  // B' = (N' - B n') / n, B'' = (N'' - 2 B' n' - B n'') / n with n' = B.N', n'' = B'.N' + B.N''.
  const Vec3 n0 = c1.cross(d);
  const double n = n0.norm();
  Vec3 b, b1 = Vec3::Zero(), b2 = Vec3::Zero();
  if (n > kEndOnRel * c1.norm() * d.norm() && n > 0.0) {
    b = n0 / n;
    const Vec3 n1 = c2.cross(d) + c1.cross(d1);
    const Vec3 n2 = c3.cross(d) + 2.0 * c2.cross(d1) + c1.cross(d2);
    const double nd1 = b.dot(n1);
    b1 = (n1 - b * nd1) / n;
    const double nd2 = b1.dot(n1) + b.dot(n2);
    b2 = (n2 - 2.0 * b1 * nd1 - b * nd2) / n;
  } else {
    // Seen end-on: any direction across the line of sight.
    int axis = 0;
    d.cwiseAbs().minCoeff(&axis);
    b = d.cross(Vec3::Unit(axis)).normalized();
    if (!b.allFinite()) b = Vec3::UnitX();
  }
  const double s = u - 0.5;
  const double w = v == 1.0 ? w1_ : w0_ + (w1_ - w0_) * v, w1 = w1_ - w0_;
  out->p = c + s * w * b;
  if (!Wants(order, DerivOrder::First)) return;
  out->dpdu = w * b;
  out->dpdv = c1 + s * (w1 * b + w * b1);
  if (!Wants(order, DerivOrder::Second)) return;
  out->d2pdu2 = Vec3::Zero();
  out->d2pduv = w1 * b + w * b1;
  out->d2pdv2 = c2 + s * (2.0 * w1 * b1 + w * b2);
}

std::string CurveRibbon::Describe() const {
  std::ostringstream s;
  s << "curve width " << w0_ << ".." << w1_;
  return s.str();
}

}  // namespace patchscan
