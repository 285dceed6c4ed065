// θ trackers and turn trackers (Blinn 1978 §4.1, §4.3) as kernels: each solves for one point
// of a scan line by bivariate Newton, from a start on the line before (or from a crawl's
// interpolated point), so the X scan can carry θ-sampled chains from line to line.
//
// In perspective the surface normal N is resolved in the scan plane (the plane
// through the eye and the scan line) into T = -N·r, towards the eye along the view ray r
// (zero on the silhouette), and S = N·s, sideways along s = r × q, q the scan plane's unit
// normal; θ = atan2(T, S). A θ tracker of table angle θ_i follows G_i = S sin θ_i -
// T cos θ_i = 0 on the scan line; a turn tracker follows the zeros of θ's derivative along
// the level curve (§4.3's T(u,v), here called the turn function to keep T for the toward-
// eye component).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>

#include <Eigen/Geometry>

#include "core/vec.h"
#include "patch/surface.h"
#include "tracker/edge_scan.h"
#include "tracker/level_point.h"
#include "tracker/newton.h"

namespace patchscan {

// The frame the angle θ is measured in: the eye and the camera's right vector (world).
struct ThetaFrame {
  Vec3 eye, right, forward;
  bool orthographic = false;  // view rays all along `forward`
  // The surface's object-to-world map (the θ trackers differentiate the world normal),
  // and (cos θ_i, sin θ_i) for i < N (empty: computed when needed).
  const Affine3* worldFromObject = nullptr;
  std::span<const Vec2> angles;
  // Whether that map is the identity (a patch file's surfaces, an untransformed cage): the
  // trackers then take object derivatives as world ones, without the products. False is
  // always right, only slower.
  bool worldIsObject = false;
  // θ of world normal n at world point p, in (-π, π].
  double Theta(const Vec3& p, const Vec3& n) const {
    const Vec3 r = Ray(p);
    return ThetaOn(r, ScanPlaneNormal(r), n);
  }
  // The angle of unit normal n out of the scan plane at p, in [-π/2, π/2]: what θ does
  // not see.
  double Tilt(const Vec3& p, const Vec3& n) const { return TiltOn(ScanPlaneNormal(Ray(p)), n); }
  // Both at once (the ray and the scan plane found once): {θ, tilt}; and, given `inView`,
  // n in the view's frame there (InView).
  std::pair<double, double> Angles(const Vec3& p, const Vec3& n, Vec3* inView = nullptr) const {
    const Vec3 r = Ray(p), plane = ScanPlaneNormal(r);
    if (inView) *inView = InView(r, plane, n);
    return {ThetaOn(r, plane, n), TiltOn(plane, n)};
  }
  // Unit normal n in the view's frame at a point with view ray r and scan plane normal
  // `plane`: (S, T, sin tilt), S = n·s sideways in the plane, T = -n·r towards the eye
  // (θ = atan2(T, S)). A unit vector: s = r × plane, r and plane are orthonormal.
  static Vec3 InView(const Vec3& r, const Vec3& plane, const Vec3& n) {
    return Vec3(n.dot(r.cross(plane)), -n.dot(r), n.dot(plane));
  }
  // The unit view ray to p, and the unit normal of the scan plane through it.
  Vec3 Ray(const Vec3& p) const { return orthographic ? forward : Vec3((p - eye).normalized()); }
  Vec3 ScanPlaneNormal(const Vec3& r) const { return right.cross(r).normalized(); }
  static double ThetaOn(const Vec3& r, const Vec3& plane, const Vec3& n) {
    const Vec3 side = r.cross(plane);
    return std::atan2(-n.dot(r), n.dot(side));
  }
  static double TiltOn(const Vec3& plane, const Vec3& n) { return std::asin(std::clamp(n.dot(plane), -1.0, 1.0)); }
  const Affine3& World() const {
    static const Affine3 kIdentity = Affine3::Identity();
    return worldFromObject ? *worldFromObject : kIdentity;
  }
};

// G_i of a θ tracker at a surface point (§4.1 in the perspective form above): G_i =
// N·(s sin θ_i + r cos θ_i), here divided by |N| so that it is the sine of the angle from
// θ_i times the in-plane part of the unit normal. `grad` is its (u,v) gradient (the
// normal's derivatives and, in perspective, the turning of r and s along the surface);
// `along` = (S cos θ_i + T sin θ_i) / |N| is positive on θ_i's own side (negative at
// θ_i + π, the other root of G_i), and t = T / |N|.
struct TableResidual {
  double g = 0.0, along = 0.0, t = 0.0;
  Vec2 grad = Vec2::Zero();
};
TableResidual TableFunction(const SurfaceDerivs& object, const ThetaFrame& frame, const Vec2& angle);

// §4.3's turn function: θ's derivative along the level curve y = const at a surface
// point, per unit (u,v) length along the curve's tangent (-y_v, y_u)/|∇y| (radians per
// unit of (u,v)); zero at a turn point. NaN where the normal is perpendicular to the scan
// plane (θ undefined). `gradY` is screen y's (u,v) gradient there.
double TurnFunction(const SurfaceDerivs& object, const Vec2& gradY, const ThetaFrame& frame);
// The same from G_i's residual at a point where θ = θ_i (a solved θ tracker): there G_i's
// gradient is -ρ ∇θ, with ρ = `along`.
double TurnRate(const TableResidual& atOwnAngle, const Vec2& gradY);

// The derivative of the unit world normal (FragmentAt's) at a point with second
// derivatives `o` as (u,v) moves by `duv` (LevelPoint::UvPerPixelAlongRow: per pixel along
// the scan line, the tangent a θ chain's vertex gives its chords). NaN where undefined: a
// collapsed normal, or an infinite duv (on the silhouette).
Vec3 NormalSlope(const SurfaceDerivs& o, const Vec2& duv, const ThetaFrame& frame);

// A turn tracker's turn function is solved to this (radians per unit of (u,v)): where θ
// turns at a rate of 1 per unit² of (u,v) (a gentle crinkle), the point is within 1e-7 of
// (u,v) of the turn.
constexpr double kTurnTol = 1e-7;
// The turn function's (u,v) gradient is taken by forward differences this wide (it would
// need the surface's third derivatives): truncation ~h |T''| / 2 and rounding ~1e-16 / h
// make its relative error about 1e-6, which slows Newton's convergence by as little (the
// residual, not the Jacobian, decides where it ends).
constexpr double kTurnDiffUv = 1e-6;
// Broyden's update of that gradient (SolveTurnTracker) is skipped for a step shorter than
// this: the turn function's rounding (~1e-16 of its size) over a shorter step would be
// more than 1e-6 of the gradient.
constexpr double kTurnSecantMinUv = 1e-10;
// A θ tracker's G_i is solved to this: the sine of the angle from θ_i (radians near 0),
// far below the 1e-3 px a vertex may move for a section of radius 1e4 px.
constexpr double kThetaTol = 1e-10;
// A Newton iteration of a θ tracker runs at most this long (a start one line away
// converges in two or three).
constexpr int kThetaMaxIterations = 12;

// The turn function at uv (NaN where undefined, or where the point is not ok).
template <class ShapeT>
double TurnAt(const ShapeT& shape, const ScreenMap& map, const ThetaFrame& frame, const Vec2& uv) {
  const LevelPoint p = EvalLevelPoint(shape, map, uv, DerivOrder::Second);
  return p.ok ? TurnFunction(p.object, p.gradY, frame) : NAN;
}

// A tracker's rate along the scan lines, d(u,v)/d(ys), from its system's Jacobian J at the
// solution (rows: y's gradient, then the other function's, which does not depend on ys):
// J⁻¹ (1, 0). NaN where J is singular. The next line's start is predicted from it
// (ThetaWalker::Advance).
inline Vec2 RateAlongLines(const Mat2& jac) {
  const double det = jac.determinant();
  if (SingularJacobian(jac, det)) return Vec2(NAN, NAN);
  return Vec2(jac(1, 1), -jac(1, 0)) / det;
}

// The θ tracker of angle (cos θ_i, sin θ_i) on scan line ys by damped Newton on
// (y - ys, G_i) from `start`: false if it does not converge or leaves [0,1]² (the tracker
// has left the patch). Adds its iterations to *iterations; `residual`, if given, receives
// G_i's residual at the solution, and `rate` its rate along the lines (RateAlongLines).
// Never allocates.
template <class ShapeT>
bool SolveThetaTracker(const ShapeT& shape, const ScreenMap& map, double ys, const ThetaFrame& frame,
                       const Vec2& angle, const Vec2& start, LevelPoint* out, std::int64_t* iterations,
                       TableResidual* residual = nullptr, Vec2* rate = nullptr) {
  NewtonOptions opt;
  opt.maxIterations = kThetaMaxIterations;
  opt.domain = DomainRule::Fail;  // a tracker leaving [0,1]² has left the patch
  Mat2 last;  // the Jacobian of the last evaluation, at out->uv
  const auto r = SolveNewton2(
      [&](const Vec2& uv, Vec2* f, Mat2* jac) {
        *out = EvalLevelPoint(shape, map, uv, DerivOrder::Second);
        const TableResidual g = TableFunction(out->object, frame, angle);
        if (residual) *residual = g;
        *f = Vec2(out->y - ys, g.g);
        jac->row(0) = out->gradY.transpose();
        jac->row(1) = g.grad.transpose();
        last = *jac;
        // Blinn's damping (§4.1): a point where the normal's in-plane direction has
        // flipped (the other root θ_i + π of G_i) or T has changed sign is no decrease,
        // so the solver halves the step that reached it.
        if (!out->ok || !(g.along > 0.0) || !(g.t * angle.y() > 0.0)) *f = Vec2(NAN, NAN);
      },
      start, Vec2(kEdgeTolPx, kThetaTol), opt);
  *iterations += r.iterations;
  if (r.status != NewtonStatus::Converged) return false;
  if (out->uv != r.uv) {
    *out = EvalLevelPoint(shape, map, r.uv, DerivOrder::Second);
    const TableResidual g = TableFunction(out->object, frame, angle);
    if (residual && out->ok) *residual = g;
    last.row(0) = out->gradY.transpose();
    last.row(1) = g.grad.transpose();
  }
  if (rate) *rate = RateAlongLines(last);
  return out->ok;
}

// The turn tracker of scan line ys (§4.3: y = ys and the turn function zero) by Newton
// from `start`, the turn function's gradient by secants and forward differences: false if
// it does not converge (a turn pair has met and gone) or leaves [0,1]². Adds its iterations to
// *iterations; `rate`, if given, receives its rate along the lines (RateAlongLines, NaN if
// the solution was not the last point evaluated). Never allocates.
template <class ShapeT>
bool SolveTurnTracker(const ShapeT& shape, const ScreenMap& map, double ys, const ThetaFrame& frame,
                      const Vec2& start, LevelPoint* out, std::int64_t* iterations, Vec2* rate = nullptr) {
  NewtonOptions opt;
  opt.maxIterations = kThetaMaxIterations;
  opt.domain = DomainRule::Fail;
  Mat2 last;  // the Jacobian of the last evaluation, at out->uv
  // The turn function's gradient: by Broyden's secant update from the last point
  // evaluated, one evaluation a point instead of three (the residual, not the gradient,
  // decides where Newton ends); by forward differences at the first point and wherever the
  // turn function has not shrunk since the last (a step the secant misjudged).
  bool known = false;
  Vec2 uvKnown, gradKnown;
  double tauKnown = NAN;
  const auto r = SolveNewton2(
      [&](const Vec2& uv, Vec2* f, Mat2* jac) {
        *out = EvalLevelPoint(shape, map, uv, DerivOrder::Second);
        const double tau = out->ok ? TurnFunction(out->object, out->gradY, frame) : NAN;
        *f = Vec2(out->y - ys, tau);
        jac->row(0) = out->gradY.transpose();
        Vec2 grad = gradKnown;
        if (!known || !(std::abs(tau) < std::abs(tauKnown))) {
          // Forward differences, stepping back from the domain's far edges.
          const double hu = uv.x() + kTurnDiffUv <= 1.0 ? kTurnDiffUv : -kTurnDiffUv;
          const double hv = uv.y() + kTurnDiffUv <= 1.0 ? kTurnDiffUv : -kTurnDiffUv;
          grad = Vec2((TurnAt(shape, map, frame, uv + Vec2(hu, 0.0)) - tau) / hu,
                      (TurnAt(shape, map, frame, uv + Vec2(0.0, hv)) - tau) / hv);
        } else if (const Vec2 s = uv - uvKnown; s.norm() >= kTurnSecantMinUv) {
          grad += ((tau - tauKnown) - gradKnown.dot(s)) / s.squaredNorm() * s;
        }
        jac->row(1) = grad.transpose();
        last = *jac;
        if (std::isfinite(tau) && grad.allFinite()) known = true, uvKnown = uv, tauKnown = tau, gradKnown = grad;
        if (!out->ok) *f = Vec2(NAN, NAN);
      },
      start, Vec2(kEdgeTolPx, kTurnTol), opt);
  *iterations += r.iterations;
  if (r.status != NewtonStatus::Converged) return false;
  if (rate) *rate = out->uv == r.uv ? RateAlongLines(last) : Vec2(NAN, NAN);
  if (out->uv != r.uv) *out = EvalLevelPoint(shape, map, r.uv);
  return out->ok;
}

// The tracker of a tilt vertex (a point a crawl put where the normal had turned a table
// step since the vertex before, out of the scan plane or in all): it keeps no level of its
// own, so it rides the surface from line to line straight along y's (u,v) gradient at
// `start` (Newton on y - ys along that line: the least (u,v) change that reaches the
// line), and the advance's link check judges whether the links on both sides still turn
// less than a step. False if it leaves [0,1]² or does not converge. Adds its iterations to
// *iterations; `rate`, if given, receives its rate along the lines, d(u,v)/d(ys) along that
// direction; `order` is the point's (LevelPoint::second). Never allocates.
template <class ShapeT>
bool SolveTiltTracker(const ShapeT& shape, const ScreenMap& map, double ys, const Vec2& start, LevelPoint* out,
                      std::int64_t* iterations, Vec2* rate = nullptr, DerivOrder order = DerivOrder::Second) {
  const Vec2 from = start.cwiseMax(0.0).cwiseMin(1.0);  // an extrapolated start may lie just outside
  *out = EvalLevelPoint(shape, map, from, order);
  const double g = out->gradY.norm();
  if (!out->ok || !(g > 0.0)) return false;
  const Vec2 dir = out->gradY / g;
  // The parameter range keeping from + t dir in [0,1]².
  double lo = -INFINITY, hi = INFINITY;
  for (int k = 0; k < 2; ++k) {
    if (dir[k] == 0.0) continue;
    const double a = -from[k] / dir[k], b = (1.0 - from[k]) / dir[k];
    lo = std::max(lo, std::min(a, b));
    hi = std::min(hi, std::max(a, b));
  }
  NewtonOptions opt;
  opt.maxIterations = kThetaMaxIterations;
  opt.domain = DomainRule::Fail;  // a tracker leaving [0,1]² has left the patch
  bool first = true;
  const auto r = SolveNewton1(
      [&](double t, double* f, double* dfdt) {
        if (!first) *out = EvalLevelPoint(shape, map, from + t * dir, order);
        first = false;
        *f = out->ok ? out->y - ys : NAN;
        *dfdt = out->gradY.dot(dir);
      },
      0.0, lo, hi, kEdgeTolPx, opt);
  *iterations += r.iterations;
  if (r.status != NewtonStatus::Converged) return false;
  if (const Vec2 uv = from + r.t * dir; out->uv != uv) *out = EvalLevelPoint(shape, map, uv, order);
  if (rate) {
    const double dydt = out->gradY.dot(dir);
    *rate = std::abs(dydt) > 0.0 ? Vec2(dir / dydt) : Vec2(NAN, NAN);
  }
  return out->ok;
}

}  // namespace patchscan
