#include "patch/quadrics.h"

#include <numbers>
#include <sstream>

namespace patchscan {
namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;

// The object box of a surface of revolution: an annular sector in (x, y) times a z range.
// rhoMin <= rhoMax may be negative (RenderMan allows negative radii): a negative rho is
// the point at |rho| turned by half a turn, so mixed signs bound the whole disk.
BoxHull RevolutionHull(double rhoMin, double rhoMax, double thetaMax, double zLo, double zHi) {
  const double t0 = std::min(0.0, thetaMax), t1 = std::max(0.0, thetaMax);
  Bounds2 xy;
  if (rhoMin >= 0.0) {
    xy = SectorBox(rhoMin, rhoMax, t0, t1);
  } else if (rhoMax <= 0.0) {
    xy = SectorBox(-rhoMax, -rhoMin, t0 + std::numbers::pi, t1 + std::numbers::pi);
  } else {
    xy = SectorBox(0.0, std::max(-rhoMin, rhoMax), 0.0, 2.0 * std::numbers::pi);
  }
  Bounds3 box;
  box.Extend(Vec3(xy.lo.x(), xy.lo.y(), std::min(zLo, zHi)));
  box.Extend(Vec3(xy.hi.x(), xy.hi.y(), std::max(zLo, zHi)));
  return BoxCorners(box);
}

// Words separated by spaces, numbers to `digits` significant digits.
template <class... T>
std::string DigitWords(int digits, const char* kind, const T&... values) {
  std::ostringstream s;
  s.precision(digits);
  s << kind;
  ((s << ' ' << values), ...);
  return s.str();
}

// For people: six digits.
template <class... T>
std::string Words(const char* kind, const T&... values) {
  return DigitWords(6, kind, values...);
}

double Deg(double rad) { return rad / kRadPerDeg; }

}  // namespace

Bounds2 SectorBox(double rhoMin, double rhoMax, double t0, double t1) {
  // x = rho cos t and y = rho sin t are linear in rho and take their extremes over t at
  // the ends of the sweep or at multiples of 90 degrees inside it.
  if (t0 > t1) std::swap(t0, t1);
  Bounds2 box;
  if (!(t1 - t0 < 2.0 * std::numbers::pi)) {
    // A whole turn or more (or a sweep beyond double's reach): the annulus's box.
    const double m = std::max(std::abs(rhoMin), std::abs(rhoMax));
    box.Extend(Vec2(-m, -m));
    box.Extend(Vec2(m, m));
    return box;
  }
  auto add = [&](double t) {
    for (double rho : {rhoMin, rhoMax}) box.Extend(Vec2(rho * std::cos(t), rho * std::sin(t)));
  };
  add(t0);
  add(t1);
  const double quarter = std::numbers::pi / 2.0;
  for (double k = std::ceil(t0 / quarter); k * quarter < t1; k += 1.0) add(k * quarter);
  return box;
}

Sphere::Sphere(double radius, double zMin, double zMax, double thetaMaxDeg)
    : RenderManQuadric({radius, zMin, zMax, thetaMaxDeg}), r_(radius), thetaMax_(thetaMaxDeg * kRadPerDeg) {
  const double r = std::abs(radius);
  const double z0 = std::clamp(std::min(zMin, zMax), -r, r);
  const double z1 = std::clamp(std::max(zMin, zMax), -r, r);
  phiMin_ = r > 0 ? std::asin(z0 / r) : 0.0;
  phiMax_ = r > 0 ? std::asin(z1 / r) : 0.0;
  auto ring = [&](double z) { return std::sqrt(std::max(r * r - z * z, 0.0)); };
  const double rhoMax = (z0 <= 0.0 && z1 >= 0.0) ? r : std::max(ring(z0), ring(z1));
  hull_ = RevolutionHull(std::min(ring(z0), ring(z1)), rhoMax, thetaMax_, z0, z1);
}
std::string Sphere::Describe() const {
  return Words("sphere radius", r_, "phi", Deg(phiMin_), Deg(phiMax_), "thetamax", Deg(thetaMax_));
}

Cylinder::Cylinder(double radius, double zMin, double zMax, double thetaMaxDeg)
    : RenderManQuadric({radius, zMin, zMax, thetaMaxDeg}),
      r_(radius), zMin_(zMin), zMax_(zMax), thetaMax_(thetaMaxDeg * kRadPerDeg) {
  hull_ = RevolutionHull(r_, r_, thetaMax_, zMin, zMax);
}
std::string Cylinder::Describe() const {
  return Words("cylinder radius", r_, "z", zMin_, zMax_, "thetamax", Deg(thetaMax_));
}

Cone::Cone(double height, double radius, double thetaMaxDeg)
    : RenderManQuadric({height, radius, thetaMaxDeg}), h_(height), r_(radius), thetaMax_(thetaMaxDeg * kRadPerDeg) {
  hull_ = RevolutionHull(std::min(0.0, r_), std::max(0.0, r_), thetaMax_, 0.0, h_);
}
std::string Cone::Describe() const {
  return Words("cone height", h_, "radius", r_, "thetamax", Deg(thetaMax_));
}

Paraboloid::Paraboloid(double rMax, double zMin, double zMax, double thetaMaxDeg)
    : RenderManQuadric({rMax, zMin, zMax, thetaMaxDeg}),
      rMax_(rMax), zMin_(zMin), zMax_(zMax), thetaMax_(thetaMaxDeg * kRadPerDeg) {
  // rho = rMax sqrt(z / zMax) is monotonic in z, so its range is set by the two ends.
  auto rho = [&](double z) { return rMax_ * std::sqrt(std::max(z / zMax_, 0.0)); };
  const double a = rho(zMin), b = rho(zMax);
  hull_ = RevolutionHull(std::min(a, b), std::max(a, b), thetaMax_, zMin, zMax);
}
std::string Paraboloid::Describe() const {
  return Words("paraboloid rmax", rMax_, "z", zMin_, zMax_, "thetamax", Deg(thetaMax_));
}

Hyperboloid::Hyperboloid(const Vec3& point1, const Vec3& point2, double thetaMaxDeg)
    : RenderManQuadric({point1.x(), point1.y(), point1.z(), point2.x(), point2.y(), point2.z(), thetaMaxDeg}),
      p1_(point1), p2_(point2), thetaMax_(thetaMaxDeg * kRadPerDeg) {
  // The sweep of a segment about z: its distance from the axis is convex along the
  // segment, so the largest is at an end; the smallest is the segment's distance to the
  // axis in the xy projection. The start angle of each point differs, so bound the full
  // annulus unless both ends start at angle 0 (then the sector rule applies).
  const Vec2 a = p1_.head<2>(), b = p2_.head<2>(), e = b - a;
  const double t = e.squaredNorm() > 0 ? std::clamp(-a.dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
  const double rhoMin = (a + t * e).norm(), rhoMax = std::max(a.norm(), b.norm());
  const bool onXAxis = a.y() == 0.0 && b.y() == 0.0 && a.x() >= 0.0 && b.x() >= 0.0;
  const double sweep = onXAxis ? thetaMax_ : 2.0 * std::numbers::pi;
  hull_ = RevolutionHull(rhoMin, rhoMax, sweep, p1_.z(), p2_.z());
}
std::string Hyperboloid::Describe() const {
  return Words("hyperboloid from", p1_.transpose(), "to", p2_.transpose(), "thetamax",
               Deg(thetaMax_));
}

Disk::Disk(double height, double radius, double thetaMaxDeg)
    : RenderManQuadric({height, radius, thetaMaxDeg}), h_(height), r_(radius), thetaMax_(thetaMaxDeg * kRadPerDeg) {
  hull_ = RevolutionHull(std::min(0.0, r_), std::max(0.0, r_), thetaMax_, h_, h_);
}
std::string Disk::Describe() const {
  return Words("disk height", h_, "radius", r_, "thetamax", Deg(thetaMax_));
}

Torus::Torus(double majorRadius, double minorRadius, double phiMinDeg, double phiMaxDeg,
             double thetaMaxDeg)
    : RenderManQuadric({majorRadius, minorRadius, phiMinDeg, phiMaxDeg, thetaMaxDeg}), major_(majorRadius),
      minor_(minorRadius),
      phiMin_(phiMinDeg * kRadPerDeg),
      phiMax_(phiMaxDeg * kRadPerDeg),
      thetaMax_(thetaMaxDeg * kRadPerDeg) {
  // The tube circle (minor cos phi, minor sin phi) over the phi sweep is an arc; its box
  // gives the range of rho = major + minor cos phi and of z = minor sin phi.
  const Bounds2 tube = minor_ >= 0.0
                           ? SectorBox(minor_, minor_, phiMin_, phiMax_)
                           : SectorBox(-minor_, -minor_, phiMin_ + std::numbers::pi,
                                       phiMax_ + std::numbers::pi);
  hull_ = RevolutionHull(major_ + tube.lo.x(), major_ + tube.hi.x(), thetaMax_, tube.lo.y(),
                         tube.hi.y());
}
std::string Torus::Describe() const {
  return Words("torus major", major_, "minor", minor_, "phi", Deg(phiMin_), Deg(phiMax_),
               "thetamax", Deg(thetaMax_));
}

Saddle::Saddle(double halfWidth) : a_(halfWidth) {
  const double a = std::abs(a_);
  Bounds3 box;
  box.Extend(Vec3(-a, -a, -a * a));
  box.Extend(Vec3(a, a, a * a));
  hull_ = BoxCorners(box);
}
std::string Saddle::Describe() const { return Words("saddle z = x^2 - y^2, half-width", a_); }

MonkeySaddle::MonkeySaddle(double halfWidth) : a_(halfWidth) {
  // On the square, x^3 - 3 x y^2 has no interior extremum; on the boundary it reaches
  // +-2 a^3 (at x = -a, y = +-a and x = a, y = +-a).
  const double a = std::abs(a_);
  Bounds3 box;
  box.Extend(Vec3(-a, -a, -2.0 * a * a * a));
  box.Extend(Vec3(a, a, 2.0 * a * a * a));
  hull_ = BoxCorners(box);
}
std::string MonkeySaddle::Describe() const {
  return Words("monkey saddle z = x^3 - 3 x y^2, half-width", a_);
}

}  // namespace patchscan
