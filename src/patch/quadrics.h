// Analytic surfaces on [0,1]^2, parameterized as RenderMan 3.2 defines its quadrics
// (angles given in degrees, u sweeping theta from 0 to thetamax), plus two test surfaces.
// Every Evaluate is inline, allocation-free and fills only the requested orders.
#pragma once

#include <array>
#include <cmath>
#include <span>
#include <string>

#include "patch/surface_derivs.h"

namespace patchscan {

// x, y bounds of the annular sector {rho (cos t, sin t) : rho in [rhoMin, rhoMax],
// t between t0 and t1 (radians)}, 0 <= rhoMin <= rhoMax. Exact, not just conservative.
Bounds2 SectorBox(double rhoMin, double rhoMax, double t0, double t1);

namespace detail {
// The u-derivatives shared by every surface of revolution p = (rho cos t, rho sin t, z)
// with t = u * thetaMax: d/du rotates (x, y) by 90 degrees and scales by thetaMax.
inline void RevolveU(const Vec3& p, double thetaMax, bool first, bool second, SurfaceDerivs* d) {
  if (first) d->dpdu = Vec3(-p.y(), p.x(), 0.0) * thetaMax;
  if (second) d->d2pdu2 = Vec3(p.x(), p.y(), 0.0) * (-thetaMax * thetaMax);
}

// The angle t reduced to (-pi, pi]: exact (Sterbenz) for t in [-2 pi, 2 pi], so a full
// turn's two ends, u = 0 and u = 1 with thetamax 360, give the same sine and cosine bit for
// bit and the seam's two edges are one curve (sin(2 pi) is -2.4e-16 in doubles: the edges
// 1e-14 px apart left a crack for samples lying exactly on them).
inline double Turn(double t) {
  constexpr double kPi = 3.141592653589793, kTwoPi = 6.283185307179586;
  return t > kPi ? t - kTwoPi : (t <= -kPi ? t + kTwoPi : t);
}
}  // namespace detail

// What each RenderMan quadric keeps beside its shape: its hull (a box about its swept
// profile) and the N arguments it was made from, as given, in the request's order (what
// makes the same surface again: scene/rib/writer.cpp).
template <std::size_t N>
class RenderManQuadric {
 public:
  std::span<const Vec3> Hull() const { return hull_; }
  std::span<const double> Given() const { return given_; }

 protected:
  explicit RenderManQuadric(const std::array<double, N>& given) : given_(given) {}
  BoxHull hull_;

 private:
  std::array<double, N> given_;
};

// Sphere: radius, zmin, zmax (clamped to [-radius, radius]), thetamax.
class Sphere : public RenderManQuadric<4> {
 public:
  Sphere(double radius, double zMin, double zMax, double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;
  double Radius() const { return r_; }

 private:
  double r_, phiMin_, phiMax_, thetaMax_;
};

// Cylinder: radius, zmin, zmax, thetamax.
class Cylinder : public RenderManQuadric<4> {
 public:
  Cylinder(double radius, double zMin, double zMax, double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;

 private:
  double r_, zMin_, zMax_, thetaMax_;
};

// Cone: height, base radius, thetamax; base circle at z = 0, apex at (0, 0, height) for v = 1.
class Cone : public RenderManQuadric<3> {
 public:
  Cone(double height, double radius, double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;

 private:
  double h_, r_, thetaMax_;
};

// Paraboloid: rmax, zmin, zmax, thetamax; radius rmax * sqrt(z / zmax).
// At the apex (z = 0) the true v-derivative is unbounded; see kParaboloidApexRatio.
class Paraboloid : public RenderManQuadric<4> {
 public:
  Paraboloid(double rMax, double zMin, double zMax, double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;

  // z / zmax is floored at this ratio when derivatives are taken, so that the collapsed
  // apex edge yields large finite derivatives (a rho' of about 5e5 * rmax) instead of inf.
  static constexpr double kParaboloidApexRatio = 1e-30;

 private:
  double rMax_, zMin_, zMax_, thetaMax_;
};

// Hyperboloid: the segment point1 -> point2 swept about the z axis by thetamax.
class Hyperboloid : public RenderManQuadric<7> {
 public:
  Hyperboloid(const Vec3& point1, const Vec3& point2, double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;

 private:
  Vec3 p1_, p2_;
  double thetaMax_;
};

// Disk: height, radius, thetamax; v = 0 on the rim, v = 1 at the centre.
class Disk : public RenderManQuadric<3> {
 public:
  Disk(double height, double radius, double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;

 private:
  double h_, r_, thetaMax_;
};

// Torus: major radius, minor radius, phimin, phimax (the tube angle), thetamax.
class Torus : public RenderManQuadric<5> {
 public:
  Torus(double majorRadius, double minorRadius, double phiMinDeg, double phiMaxDeg,
        double thetaMaxDeg);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::string Describe() const;

 private:
  double major_, minor_, phiMin_, phiMax_, thetaMax_;
};

// Test surface z = x^2 - y^2 over the square x, y in [-a, a] (x = a(2u-1), y = a(2v-1)).
class Saddle {
 public:
  explicit Saddle(double halfWidth);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::span<const Vec3> Hull() const { return hull_; }
  std::string Describe() const;

 private:
  double a_;
  BoxHull hull_;
};

// Test surface z = x^3 - 3 x y^2 (the monkey saddle) over the square x, y in [-a, a].
class MonkeySaddle {
 public:
  explicit MonkeySaddle(double halfWidth);
  void Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const;
  std::span<const Vec3> Hull() const { return hull_; }
  std::string Describe() const;

 private:
  double a_;
  BoxHull hull_;
};

// ---- inline evaluation ----

inline void Sphere::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_), dPhi = phiMax_ - phiMin_, phi = phiMin_ + v * dPhi;
  const double ct = std::cos(theta), st = std::sin(theta), cp = std::cos(phi), sp = std::sin(phi);
  d->p = Vec3(r_ * ct * cp, r_ * st * cp, r_ * sp);
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  if (first) d->dpdv = dPhi * Vec3(-r_ * ct * sp, -r_ * st * sp, r_ * cp);
  if (second) {
    d->d2pduv = thetaMax_ * dPhi * Vec3(r_ * st * sp, -r_ * ct * sp, 0.0);
    d->d2pdv2 = -dPhi * dPhi * d->p;
  }
}

inline void Cylinder::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_);
  d->p = Vec3(r_ * std::cos(theta), r_ * std::sin(theta), zMin_ + v * (zMax_ - zMin_));
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  if (first) d->dpdv = Vec3(0.0, 0.0, zMax_ - zMin_);
  if (second) d->d2pduv = d->d2pdv2 = Vec3::Zero();
}

inline void Cone::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_), ct = std::cos(theta), st = std::sin(theta);
  const double rho = r_ * (1.0 - v);
  d->p = Vec3(rho * ct, rho * st, v * h_);
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  if (first) d->dpdv = Vec3(-r_ * ct, -r_ * st, h_);
  if (second) {
    d->d2pduv = thetaMax_ * Vec3(r_ * st, -r_ * ct, 0.0);
    d->d2pdv2 = Vec3::Zero();
  }
}

inline void Paraboloid::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_), ct = std::cos(theta), st = std::sin(theta);
  const double dz = zMax_ - zMin_, z = zMin_ + v * dz;
  const double q = std::max(z / zMax_, 0.0);  // rho = rMax sqrt(q)
  const double rho = rMax_ * std::sqrt(q);
  d->p = Vec3(rho * ct, rho * st, z);
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  if (first || second) {
    // d rho / dv = rMax q' / (2 sqrt q), q' = dz / zMax;  d2 rho / dv2 = -rMax q'^2 / (4 q^1.5).
    const double qd = std::max(q, kParaboloidApexRatio), sq = std::sqrt(qd), qv = dz / zMax_;
    const double rhoV = rMax_ * qv / (2.0 * sq);
    if (first) d->dpdv = Vec3(rhoV * ct, rhoV * st, dz);
    if (second) {
      const double rhoVV = -rMax_ * qv * qv / (4.0 * qd * sq);
      d->d2pduv = thetaMax_ * rhoV * Vec3(-st, ct, 0.0);
      d->d2pdv2 = Vec3(rhoVV * ct, rhoVV * st, 0.0);
    }
  }
}

inline void Hyperboloid::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_), ct = std::cos(theta), st = std::sin(theta);
  const Vec3 l = p1_ + v * (p2_ - p1_), e = p2_ - p1_;
  d->p = Vec3(l.x() * ct - l.y() * st, l.x() * st + l.y() * ct, l.z());
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  const Vec3 eRot(e.x() * ct - e.y() * st, e.x() * st + e.y() * ct, e.z());
  if (first) d->dpdv = eRot;
  if (second) {
    d->d2pduv = thetaMax_ * Vec3(-eRot.y(), eRot.x(), 0.0);
    d->d2pdv2 = Vec3::Zero();
  }
}

inline void Disk::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_), ct = std::cos(theta), st = std::sin(theta);
  const double rho = r_ * (1.0 - v);
  d->p = Vec3(rho * ct, rho * st, h_);
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  if (first) d->dpdv = Vec3(-r_ * ct, -r_ * st, 0.0);
  if (second) {
    d->d2pduv = thetaMax_ * Vec3(r_ * st, -r_ * ct, 0.0);
    d->d2pdv2 = Vec3::Zero();
  }
}

inline void Torus::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const bool first = Wants(order, DerivOrder::First), second = Wants(order, DerivOrder::Second);
  const double theta = detail::Turn(u * thetaMax_), ct = std::cos(theta), st = std::sin(theta);
  const double dPhi = phiMax_ - phiMin_, phi = detail::Turn(phiMin_ + v * dPhi);
  const double cp = std::cos(phi), sp = std::sin(phi), rho = major_ + minor_ * cp;
  d->p = Vec3(rho * ct, rho * st, minor_ * sp);
  detail::RevolveU(d->p, thetaMax_, first, second, d);
  if (first) d->dpdv = dPhi * Vec3(-minor_ * sp * ct, -minor_ * sp * st, minor_ * cp);
  if (second) {
    d->d2pduv = thetaMax_ * dPhi * Vec3(minor_ * sp * st, -minor_ * sp * ct, 0.0);
    d->d2pdv2 = -dPhi * dPhi * Vec3(minor_ * cp * ct, minor_ * cp * st, minor_ * sp);
  }
}

inline void Saddle::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const double x = a_ * (2.0 * u - 1.0), y = a_ * (2.0 * v - 1.0), s = 2.0 * a_;  // s = dx/du
  d->p = Vec3(x, y, x * x - y * y);
  if (Wants(order, DerivOrder::First)) {
    d->dpdu = Vec3(s, 0.0, 2.0 * x * s);
    d->dpdv = Vec3(0.0, s, -2.0 * y * s);
  }
  if (Wants(order, DerivOrder::Second)) {
    d->d2pdu2 = Vec3(0.0, 0.0, 2.0 * s * s);
    d->d2pduv = Vec3::Zero();
    d->d2pdv2 = Vec3(0.0, 0.0, -2.0 * s * s);
  }
}

inline void MonkeySaddle::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* d) const {
  const double x = a_ * (2.0 * u - 1.0), y = a_ * (2.0 * v - 1.0), s = 2.0 * a_;
  d->p = Vec3(x, y, x * x * x - 3.0 * x * y * y);
  if (Wants(order, DerivOrder::First)) {
    d->dpdu = Vec3(s, 0.0, s * (3.0 * x * x - 3.0 * y * y));
    d->dpdv = Vec3(0.0, s, s * (-6.0 * x * y));
  }
  if (Wants(order, DerivOrder::Second)) {
    d->d2pdu2 = Vec3(0.0, 0.0, s * s * 6.0 * x);
    d->d2pduv = Vec3(0.0, 0.0, s * s * -6.0 * y);
    d->d2pdv2 = Vec3(0.0, 0.0, s * s * -6.0 * x);
  }
}

}  // namespace patchscan
